//! Plinth field box: acquisition pipeline and drivers (target independent).
#![no_std]
