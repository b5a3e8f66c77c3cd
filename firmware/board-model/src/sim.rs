//! The CPU side of the model: the NVIC (level-sensitive lines latched as
//! pending, priorities, preemption, PRIMASK windows) and the cost of the
//! code. Firmware code runs natively on the host; every register or RAM
//! access it makes through a [`Port`] lets the board's time pass by the
//! access's cost first, so hardware events, and the interrupts they raise,
//! interleave with the code at tick resolution. An interrupt whose
//! priority is above the running code's preempts it at the next access.

use crate::hw::{Hw, RAM_BASE, RAM_BYTES};
use plinth_firmware::clock::Registers;
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// CPU cycles of exception entry (stacking) and of exit (Cortex-M4, no FPU
/// context).
pub const ENTRY_CYCLES: u64 = 12;
/// CPU cycles of exception exit.
pub const EXIT_CYCLES: u64 = 12;
/// CPU cycles of a peripheral register access (APB through the bus matrix).
pub const PERIPHERAL_CYCLES: u64 = 4;
/// CPU cycles of a RAM access.
pub const RAM_CYCLES: u64 = 1;

/// An interrupt handler: the firmware's handler body on a port.
pub type Handler = Box<dyn FnMut(&mut Port)>;

/// One interrupt source.
struct Irq {
    number: u32,
    priority: u8,
    name: &'static str,
    handler: Option<Handler>,
    pending: bool,
    active: bool,
    /// Calls, register accesses, and cycles spent in it (less the time
    /// of handlers that preempted it).
    calls: u64,
    accesses: u64,
    cycles: i64,
    /// Tick it last became pending, and the longest wait from pending to
    /// entry [ticks].
    pended_at: u64,
    max_wait: u64,
}

/// Per-handler figures.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HandlerStats {
    /// Handler name.
    pub name: &'static str,
    /// Priority (higher preempts lower).
    pub priority: u8,
    /// Calls.
    pub calls: u64,
    /// Register and RAM accesses in all calls.
    pub accesses: u64,
    /// CPU cycles in all calls, entry and exit included.
    pub cycles: u64,
    /// Longest wait from pending to entry [CPU cycles] (higher-priority
    /// handlers, masked windows and critical sections at or above its
    /// priority).
    pub max_wait_cycles: u64,
}

/// The simulated board: hardware, NVIC, interrupt masking.
pub struct Board {
    /// The peripherals.
    pub hw: RefCell<Hw>,
    irqs: RefCell<Vec<Irq>>,
    /// Priority of the running code (0: thread).
    level: Cell<u8>,
    /// Interrupts masked (PRIMASK) in these windows [ticks].
    masked: RefCell<Vec<(u64, u64)>>,
    /// CPU cycles per tick.
    cycles_per_tick: u64,
    /// Accesses made in the innermost running handler.
    counting: Cell<Option<usize>>,
    /// Longest critical section ([`Board::with_ceiling`]) [ticks].
    longest_section: Cell<u64>,
}

/// The firmware's view of the board: register and RAM access by address.
#[derive(Clone)]
pub struct Port(pub Rc<Board>);

impl Board {
    /// A board whose core runs at `cycles_per_tick` CPU cycles per timer tick.
    pub fn new(hw: Hw, cycles_per_tick: u64) -> Rc<Self> {
        Rc::new(Self {
            hw: RefCell::new(hw),
            irqs: RefCell::new(Vec::new()),
            level: Cell::new(0),
            masked: RefCell::new(Vec::new()),
            cycles_per_tick: cycles_per_tick.max(1),
            counting: Cell::new(None),
            longest_section: Cell::new(0),
        })
    }

    /// Connects `handler` to IRQ `number` at `priority`.
    pub fn attach(&self, number: u32, priority: u8, name: &'static str, handler: Handler) {
        self.irqs.borrow_mut().push(Irq {
            number,
            priority,
            name,
            handler: Some(handler),
            pending: false,
            active: false,
            calls: 0,
            accesses: 0,
            cycles: 0,
            pended_at: 0,
            max_wait: 0,
        });
    }

    /// Pends IRQ `number` from software (RTIC's `pend`: a task's
    /// dispatcher).
    pub fn pend(&self, number: u32) {
        let now = self.now();
        for irq in self.irqs.borrow_mut().iter_mut() {
            if irq.number == number && !irq.pending {
                irq.pending = true;
                irq.pended_at = now;
            }
        }
    }

    /// Runs `f` with the running priority raised to `ceiling` (an RTIC
    /// lock: the stack resource policy's critical section); interrupts at
    /// or below the ceiling wait, and run as soon as it ends.
    pub fn with_ceiling<R>(self: &Rc<Self>, ceiling: u8, f: impl FnOnce() -> R) -> R {
        let outer = self.level.get();
        self.level.set(outer.max(ceiling));
        let start = self.now();
        let r = f();
        let held = self.now() - start;
        self.longest_section
            .set(self.longest_section.get().max(held));
        self.level.set(outer);
        self.run_until(self.now());
        r
    }

    /// Longest critical section so far [CPU cycles] (preempting handlers
    /// included).
    pub fn longest_section_cycles(&self) -> u64 {
        self.longest_section.get() * self.cycles_per_tick
    }

    /// Masks every interrupt from `from` for `ticks` (a critical section:
    /// a log write, a debugger).
    pub fn mask(&self, from: u64, ticks: u64) {
        self.masked.borrow_mut().push((from, from + ticks));
    }

    /// Current tick.
    pub fn now(&self) -> u64 {
        self.hw.borrow().now
    }

    /// Figures per handler.
    pub fn stats(&self) -> Vec<HandlerStats> {
        self.irqs
            .borrow()
            .iter()
            .map(|i| HandlerStats {
                name: i.name,
                priority: i.priority,
                calls: i.calls,
                accesses: i.accesses,
                cycles: i.cycles.max(0) as u64,
                max_wait_cycles: i.max_wait * self.cycles_per_tick,
            })
            .collect()
    }

    fn masked_at(&self, t: u64) -> Option<u64> {
        self.masked
            .borrow()
            .iter()
            .filter(|w| t >= w.0 && t < w.1)
            .map(|w| w.1)
            .max()
    }

    /// Latches asserted lines as pending; applies NVIC clear-pending writes.
    fn latch(&self) {
        let mut hw = self.hw.borrow_mut();
        let clear = std::mem::take(&mut hw.nvic_clear);
        let now = hw.now;
        for irq in self.irqs.borrow_mut().iter_mut() {
            if clear & (1u64 << irq.number) != 0 {
                irq.pending = false;
            }
            if !irq.active && hw.irq_line(irq.number) {
                if !irq.pending {
                    irq.pended_at = now;
                }
                irq.pending = true;
            }
        }
    }

    /// The pending interrupt that would preempt the running code now.
    fn preempting(&self) -> Option<usize> {
        if self.masked_at(self.now()).is_some() {
            return None;
        }
        let level = self.level.get();
        let irqs = self.irqs.borrow();
        irqs.iter()
            .enumerate()
            .filter(|(_, i)| i.pending && i.priority > level)
            .max_by_key(|(k, i)| (i.priority, usize::MAX - k))
            .map(|(k, _)| k)
    }

    /// Lets time pass to `target`, running hardware events and whatever
    /// interrupts preempt the current code.
    pub fn run_until(self: &Rc<Self>, target: u64) {
        loop {
            self.latch();
            if let Some(k) = self.preempting() {
                self.run_handler(k);
                continue;
            }
            let now = self.now();
            if now >= target {
                return;
            }
            let mut next = self.hw.borrow().next_event().unwrap_or(target).min(target);
            if let Some(end) = self.masked_at(now) {
                next = next.min(end);
            } else if let Some(start) = self
                .masked
                .borrow()
                .iter()
                .map(|w| w.0)
                .filter(|&s| s > now)
                .min()
            {
                next = next.min(start);
            }
            self.hw.borrow_mut().process(next.max(now));
        }
    }

    /// Spends `cycles` CPU cycles of the running code.
    pub fn spend(self: &Rc<Self>, cycles: u64) {
        let ticks = cycles.div_ceil(self.cycles_per_tick);
        let target = self.now() + ticks;
        self.run_until(target);
    }

    fn run_handler(self: &Rc<Self>, k: usize) {
        let (priority, mut handler) = {
            let mut irqs = self.irqs.borrow_mut();
            let irq = &mut irqs[k];
            irq.pending = false;
            irq.active = true;
            irq.calls += 1;
            let waited = self.hw.borrow().now.saturating_sub(irq.pended_at);
            irq.max_wait = irq.max_wait.max(waited);
            (irq.priority, irq.handler.take())
        };
        let outer_level = self.level.replace(priority);
        let outer_count = self.counting.replace(Some(k));
        let start = self.now();
        self.spend(ENTRY_CYCLES);
        if let Some(h) = handler.as_mut() {
            h(&mut Port(self.clone()));
        }
        self.spend(EXIT_CYCLES);
        let spent = (self.now() - start) * self.cycles_per_tick;
        self.counting.set(outer_count);
        self.level.set(outer_level);
        let mut irqs = self.irqs.borrow_mut();
        let irq = &mut irqs[k];
        irq.active = false;
        irq.handler = handler;
        // (Time spent in preempting handlers is theirs, not this one's.)
        irq.cycles += spent as i64;
        if let Some(outer) = outer_count {
            irqs[outer].cycles -= spent as i64;
        }
    }

    fn access(self: &Rc<Self>, addr: usize) {
        let ram = (RAM_BASE..RAM_BASE + RAM_BYTES).contains(&addr);
        if let Some(k) = self.counting.get() {
            self.irqs.borrow_mut()[k].accesses += 1;
        }
        self.spend(if ram { RAM_CYCLES } else { PERIPHERAL_CYCLES });
    }
}

impl Registers for Port {
    fn read(&mut self, addr: usize) -> u32 {
        self.0.access(addr);
        self.0.hw.borrow_mut().read(addr)
    }

    fn write(&mut self, addr: usize, value: u32) {
        self.0.access(addr);
        self.0.hw.borrow_mut().write(addr, value);
    }
}
