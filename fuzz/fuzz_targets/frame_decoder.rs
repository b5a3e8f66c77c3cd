#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| plinth_fuzz::frame_decoder(data));
