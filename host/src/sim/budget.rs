//! How much memory a simulation needs, estimated before anything large is
//! allocated, against what the machine has.

use super::machine::Machine;

/// Estimated peak memory [bytes] of `simulate` on `machine` over `speeds`
/// speeds: the banded model (five real band arrays and one complex working
/// matrix, LAPACK storage with fill-in rows), the per-speed results and the
/// run directory's rows. Shaft node responses are not kept by `simulate`.
pub fn simulate_bytes(machine: &Machine, speeds: usize) -> u64 {
    let pedestals = machine
        .bearings
        .iter()
        .filter(|b| b.pedestal.is_some())
        .count() as u64;
    let most_at_a_node = (0..machine.node_positions.len())
        .map(|n| {
            machine
                .bearings
                .iter()
                .filter(|b| b.node == n && b.pedestal.is_some())
                .count()
        })
        .max()
        .unwrap_or(0) as u64;
    model_bytes(
        machine.node_positions.len() as u64,
        pedestals,
        most_at_a_node,
        machine.bearings.len() as u64,
        speeds,
    )
}

/// [`simulate_bytes`] from the counts alone: `nodes` shaft nodes,
/// `pedestals` pedestals (at most `most_at_a_node` at one node), `bearings`
/// bearings, `speeds` speeds [bytes] (saturating: never overflows).
pub fn model_bytes(
    nodes: u64,
    pedestals: u64,
    most_at_a_node: u64,
    bearings: u64,
    speeds: usize,
) -> u64 {
    let n_dof = nodes.saturating_mul(4).saturating_add(2 * pedestals);
    let half_band = 7 + 2 * most_at_a_node;
    let ldab = 3 * half_band + 1;
    // Five real band arrays, plus one complex working matrix per solver
    // thread, and the DOF scales.
    let threads = solver_threads(usize::try_from(n_dof).unwrap_or(usize::MAX), speeds) as u64;
    let band = n_dof
        .saturating_mul(ldab * 8 * (5 + 2 * threads))
        .saturating_add(n_dof.saturating_mul(8));
    let per_row = 640; // result, measurement and bearing row per speed and bearing
    let rows = (speeds as u64)
        .saturating_mul(bearings)
        .saturating_mul(per_row);
    // Solution, load and the refinement's right-hand side and residual
    // (complex, per DOF); node data and each element's stiffness form.
    let vectors = n_dof
        .saturating_mul(16 * 6)
        .saturating_add(nodes.saturating_mul(64 + 4));
    band.saturating_add(rows)
        .saturating_add(vectors)
        .saturating_add(16 << 20)
}

/// Estimated peak memory [bytes] of reading a machine file of `elements`
/// shaft elements with `bearings` bearings and solving its model at one
/// speed: the elements and node positions (48 + 8 bytes each), the static
/// bearing loads' band matrix (two DOFs per node, 10 complex rows) and
/// [`model_bytes`] at one speed. Checked before the shaft is built.
pub fn machine_bytes(elements: u64, bearings: u64) -> u64 {
    let nodes = elements.saturating_add(1);
    let shaft = elements
        .saturating_mul(48)
        .saturating_add(nodes.saturating_mul(8));
    let static_load = nodes.saturating_mul(2 * 10 * 16 + 2 * 16 + 8);
    shaft
        .saturating_add(static_load)
        .saturating_add(model_bytes(nodes, bearings, bearings, bearings, 1))
}

/// Threads the unbalance response uses for a model of `n_dof` DOFs over
/// `speeds` speeds: one for small models (a thread costs more than it
/// saves), else up to the machine's cores (at most 4), never more than the
/// speeds. Each thread holds its own complex working band matrix.
pub fn solver_threads(n_dof: usize, speeds: usize) -> usize {
    if n_dof < 4000 || speeds < 2 {
        return 1;
    }
    std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, 4)
        .min(speeds)
}

/// Estimated peak memory [bytes] of `signals` on `machine`: the model (as
/// [`simulate_bytes`] over the `grid_points` + `check_points` speeds), the
/// interpolants of every channel over the grid (spline phasors per grid
/// point and channel, the Hermite knots and differences of velocity and
/// acceleration channels, plus the grid's truth rows) and the
/// ADC codes (`samples` × channels × 2 bytes, i16), all held at once.
pub fn signals_bytes(
    machine: &Machine,
    samples: u64,
    grid_points: usize,
    check_points: usize,
) -> u64 {
    let channels = 4 * machine.bearings.len() as u64;
    let model = simulate_bytes(machine, grid_points + check_points);
    // Spline (value, second derivative, knot) and, for velocity and
    // acceleration channels, the Hermite knots (value, two derivatives)
    // and their differences: 16-byte numbers per grid point and channel.
    let splines = grid_points as u64 * channels * 16 * 13;
    let codes = samples.saturating_mul(channels).saturating_mul(2);
    model.saturating_add(splines).saturating_add(codes)
}

/// Estimated peak memory [bytes] of `accuracy`: `draws` draws on a machine
/// with `bearings` pedestals over `speeds` speeds. Every draw keeps its
/// estimates and standard errors for ML and OLS (5 + 5 numbers each), the
/// bound's variances and a turn (digits), gathered once more per bearing;
/// each worker thread holds one perturbed run directory at a time.
pub fn accuracy_bytes(bearings: u64, speeds: u64, draws: u64) -> u64 {
    let per_draw = 96 + 16 + bearings.saturating_mul(2 * 80 + 40 + 2 * 80);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    let run = speeds.saturating_mul(bearings).saturating_mul(640 * 3);
    draws
        .saturating_mul(per_draw)
        .saturating_add(run.saturating_mul(threads))
        .saturating_add(16 << 20)
}

/// Refuses a count `option` (a command-line option or a file's key) whose
/// estimated memory `needed` [bytes] is beyond `available`, naming the
/// option, its value and both figures.
pub fn check_count(
    option: &str,
    value: u64,
    needed: u64,
    available: Option<u64>,
) -> Result<(), String> {
    match available {
        Some(a) if needed > a => Err(format!(
            "{option} {value}: needs about {} MB of memory and this machine has {} MB available: give a smaller {option}",
            needed >> 20,
            a >> 20
        )),
        _ => Ok(()),
    }
}

/// The environment variable that caps the memory Plinth plans for [MiB]
/// (a whole number ≥ 1): a shared machine's share, or a test's small budget.
pub const MEMORY_ENV: &str = "PLINTH_MEMORY_MB";

/// Memory this process may plan for [bytes]: what the operating system can
/// still give it (`MemAvailable` of /proc/meminfo), capped by
/// [`MEMORY_ENV`]; `None` where neither is known. An unreadable
/// `PLINTH_MEMORY_MB` is named once on stderr and not used.
pub fn available_bytes() -> Option<u64> {
    let os = os_available_bytes();
    match (os, memory_cap()) {
        (Some(a), Some(c)) => Some(a.min(c)),
        (a, c) => a.or(c),
    }
}

fn os_available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// [`MEMORY_ENV`] in bytes, if set to a whole number of MiB ≥ 1.
fn memory_cap() -> Option<u64> {
    let text = std::env::var_os(MEMORY_ENV)?;
    match parse_memory_mb(&text.to_string_lossy()) {
        Ok(b) => Some(b),
        Err(e) => {
            static WARNED: std::sync::Once = std::sync::Once::new();
            WARNED.call_once(|| eprintln!("warning: {MEMORY_ENV}: {e}; not used"));
            None
        }
    }
}

/// A [`MEMORY_ENV`] value [MiB] in bytes.
fn parse_memory_mb(text: &str) -> Result<u64, String> {
    match text.trim().parse::<u64>() {
        Ok(mb) if mb >= 1 => Ok(mb.saturating_mul(1 << 20)),
        _ => Err(format!(
            "`{}` is not a whole number of MiB >= 1",
            text.trim()
        )),
    }
}

/// A limit on the size of a request (speeds, solves), checked before any
/// work, so that a typo (`--speeds 5:200:0.001`) is refused at once instead
/// of running for an hour: the default covers every run the repository's
/// docs measure with a wide margin, and the environment variable `env`
/// raises (or lowers) it for a request that is meant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limit {
    /// What is counted, e.g. "speeds".
    pub what: &'static str,
    /// The limit when `env` is not set.
    pub default: u64,
    /// The environment variable that sets another limit (a whole number ≥ 1).
    pub env: &'static str,
    /// Why the default is what it is (shown with a refusal).
    pub why: &'static str,
}

/// Speeds of one speed list (`--speeds` of `simulate`, `paper`,
/// `accuracy`) or of one run re-predicted (`predict --against`): every
/// step after it (solves, identifications, draws, rows written) scales
/// with it. 100 000: five times the largest run measured in docs/ (20 001
/// speeds, the identify benchmark); `paper` takes about 1.3 ms CPU and
/// 11 kB per speed (5.2 s, 42 MB at 3 901 speeds), so 2 minutes and 1 GB at
/// the limit.
pub const SPEEDS: Limit = Limit {
    what: "speeds",
    default: 100_000,
    env: "PLINTH_MAX_SPEEDS",
    why: "five times the largest run measured in docs/, 20 001 speeds",
};

/// Shaft nodes × speeds of one simulated run: the response's cost grows
/// with both (docs/simulator.md: 100 000 elements at 196 speeds, 2e7 node
/// solves, take 50 s CPU, about 2.6 µs each). 1e8: five times that run,
/// about 4 minutes of CPU.
pub const NODE_SPEEDS: Limit = Limit {
    what: "shaft node x speed solves",
    default: 100_000_000,
    env: "PLINTH_MAX_NODE_SPEEDS",
    why: "five times the largest simulation measured in docs/ (100 000 elements x 196 speeds), about 4 minutes of CPU",
};

/// Rows of one table read from a file (`measurements.csv`, `bearings.csv`,
/// `resolution.csv`, `base.csv`, `transducers.csv`, an `import` table) and
/// of one run written (`simulate`, `import`: speeds × bearings): every
/// reader holds its rows, checks and sorts them. 1 000 000: five times the
/// largest run read in docs/ (200 000 rows, `plot` in 10.2 s and 121 MB,
/// docs/robustness-hostile.md), and a run at [`SPEEDS`]' limit on ten
/// bearings; the 2 000 000-row import measured there took 45 s and 1.2 GB.
pub const ROWS: Limit = Limit {
    what: "rows",
    default: 1_000_000,
    env: "PLINTH_MAX_ROWS",
    why: "five times the largest run read in docs/, 200 000 rows, and a run of 100 000 speeds on ten bearings",
};

/// A [`Limit`] counted while a file is read: [`Reading::count`] at each
/// new item (a row, a distinct speed) refuses the first one past the
/// limit, so a file far too large is never read whole.
#[derive(Clone, Copy, Debug)]
pub struct Reading {
    limit: Limit,
    /// The limit in force (its environment variable read once).
    most: u64,
    /// Items counted so far.
    seen: u64,
}

impl Reading {
    /// Counts `n` more items of `file` (a row, or the rows one table row
    /// becomes); `Err` once past the limit names the file's size [bytes],
    /// the limit, why, and the variable that raises it (the caller places
    /// it at the item's line).
    pub fn count(&mut self, file: &std::path::Path, n: u64) -> Result<(), String> {
        self.seen = self.seen.saturating_add(n);
        if self.seen <= self.most {
            return Ok(());
        }
        let size = std::fs::metadata(file).map_or(String::new(), |m| {
            format!(" (the file is {} bytes)", m.len())
        });
        let set = if self.most == self.limit.default {
            format!("the limit, {}", self.limit.why)
        } else {
            format!("the limit set by {}", self.limit.env)
        };
        Err(format!(
            "more than {} {}{size}, above the limit of {} ({set}); refused while reading, at the first of them past the limit: is it the right file? Set {}=N in the environment (a whole number above {}) to read a larger one",
            self.most,
            self.limit.what,
            self.most,
            self.limit.env,
            self.most
        ))
    }
}

impl Limit {
    /// The limit in force: `env` when set, else [`Limit::default`]; `Err`
    /// names `env` when it is not a whole number ≥ 1.
    pub fn value(&self) -> Result<u64, String> {
        match std::env::var_os(self.env) {
            None => Ok(self.default),
            Some(text) => match text.to_string_lossy().trim().parse::<u64>() {
                Ok(n) if n >= 1 => Ok(n),
                _ => Err(format!(
                    "{}={}: not a whole number >= 1 (the most {} one request may ask for)",
                    self.env,
                    text.to_string_lossy(),
                    self.what
                )),
            },
        }
    }

    /// A counter of this limit for one file being read (the environment
    /// variable read now); `Err` names the variable when it is not a whole
    /// number ≥ 1.
    pub fn reading(&self) -> Result<Reading, String> {
        Ok(Reading {
            limit: *self,
            most: self.value()?,
            seen: 0,
        })
    }

    /// Refuses `asked` above the limit: the message names `request` (the
    /// option and its value), the size asked, the limit, why it is that,
    /// and how to raise it.
    pub fn check(&self, request: &str, asked: u64) -> Result<(), String> {
        let limit = self.value()?;
        if asked <= limit {
            return Ok(());
        }
        let set = if limit == self.default {
            format!("the limit, {}", self.why)
        } else {
            format!("the limit set by {}", self.env)
        };
        Err(format!(
            "{request}: {asked} {} asked, above the limit of {limit} ({set}); refused before any work: ask for fewer, or set {}={asked} in the environment to allow it",
            self.what, self.env
        ))
    }
}

/// [`NODE_SPEEDS`] of simulating `machine` at `speeds` speeds; `request`
/// names the option and value that set the speeds.
pub fn check_solves(request: &str, machine: &Machine, speeds: usize) -> Result<(), String> {
    let nodes = machine.node_positions.len() as u64;
    NODE_SPEEDS.check(
        &format!("{request} on {nodes} shaft nodes"),
        nodes.saturating_mul(speeds as u64),
    )
}

/// Memory one row of a table costs once read [bytes]: the parsed row (speed,
/// bearing name, four phasors, noise, the digits it was written with), its
/// copies while checked and sorted, and its share of the per-speed results
/// computed from it.
pub const TABLE_ROW_BYTES: u64 = 1024;

/// The most lines a table (run directory, bearing table, 1X vector table,
/// `base.csv`) may have within `available` bytes of memory
/// ([`TABLE_ROW_BYTES`] a row); `None`: no bound known.
pub fn table_lines(available: Option<u64>) -> Option<u64> {
    available.map(|a| (a / TABLE_ROW_BYTES).max(1))
}

/// Refuses an input whose estimated memory `needed` [bytes] is beyond
/// `available`: `what` names the file and the count that sets it, and what
/// to change.
pub fn check_input(what: &str, needed: u64, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(a) if needed > a => Err(format!(
            "{what}: needs about {} MB of memory and this machine has {} MB available",
            needed.div_ceil(1 << 20),
            a >> 20
        )),
        _ => Ok(()),
    }
}

/// Refuses a request of `needed` bytes beyond `available` with both figures
/// and what to change.
pub fn check(what: &str, needed: u64, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(a) if needed > a => Err(format!(
            "{what} needs about {} MB of memory and this machine has {} MB available: use fewer shaft elements (shaft.sections[].elements) or fewer speeds",
            needed >> 20,
            a >> 20
        )),
        _ => Ok(()),
    }
}

/// [`check`] of `signals`: the message names the figures and the options
/// that set them.
pub fn check_signals(what: &str, needed: u64, available: Option<u64>) -> Result<(), String> {
    match available {
        Some(a) if needed > a => Err(format!(
            "{what} needs about {} MB of memory and this machine has {} MB available: use a shorter run (--rundown), a lower --rate, a larger --grid-step or fewer shaft elements",
            needed >> 20,
            a >> 20
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_memory_cap_is_a_whole_number_of_mib() {
        assert_eq!(super::parse_memory_mb(" 64 "), Ok(64 << 20));
        for bad in ["0", "-1", "1.5", "", "lots"] {
            let e = super::parse_memory_mb(bad).unwrap_err();
            assert!(e.contains("whole number of MiB"), "{bad}: {e}");
        }
        assert_eq!(super::table_lines(Some(1 << 20)), Some(1024));
        assert_eq!(super::table_lines(Some(10)), Some(1));
        assert_eq!(super::table_lines(None), None);
        let e = super::check_input("t.csv: 9 channels", 3 << 20, Some(1 << 20)).unwrap_err();
        assert_eq!(
            e,
            "t.csv: 9 channels: needs about 3 MB of memory and this machine has 1 MB available"
        );
        assert!(super::check_input("x", 1 << 20, Some(1 << 20)).is_ok());
    }
    #[test]
    fn a_request_above_a_limit_names_the_request_the_size_the_limit_and_the_way_up() {
        let e = super::SPEEDS
            .check("--speeds 5:200:0.001", 195_001)
            .unwrap_err();
        assert!(
            e.starts_with("--speeds 5:200:0.001: 195001 speeds asked, above the limit of 100000")
                && e.contains("set PLINTH_MAX_SPEEDS=195001"),
            "{e}"
        );
        assert!(super::SPEEDS.check("--speeds 5:205:0.01", 20_001).is_ok());
        assert!(super::NODE_SPEEDS.check("x", 100_000_000).is_ok());
        assert!(super::NODE_SPEEDS.check("x", 100_000_001).is_err());
    }
    #[test]
    fn a_billion_draws_are_refused_naming_the_option() {
        let needed = super::accuracy_bytes(2, 116, 1_000_000_000);
        assert!(needed > 600_000_000_000, "{needed}");
        let e = super::check_count("--draws", 1_000_000_000, needed, Some(16 << 30)).unwrap_err();
        assert!(
            e.starts_with("--draws 1000000000: needs about") && e.contains("16384 MB"),
            "{e}"
        );
        let small = super::accuracy_bytes(2, 116, 200);
        assert!(
            super::check_count("--draws", 200, small, Some(1 << 30)).is_ok(),
            "{small}"
        );
    }
    use super::*;

    #[test]
    fn estimate_is_linear_and_refusal_names_the_figures() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/feng-hahn-1997.toml"
        ))
        .unwrap();
        let m = Machine::from_toml_str(&text, "feng-hahn-1997.toml").unwrap();
        let a = simulate_bytes(&m, 196);
        let b = simulate_bytes(&m, 392);
        assert!(b > a && b < 2 * a);
        let e = check("simulating", 3 << 30, Some(1 << 30)).unwrap_err();
        assert!(e.contains("3072 MB") && e.contains("1024 MB"), "{e}");
        assert!(check("simulating", 1 << 20, Some(1 << 30)).is_ok());
        assert!(check("simulating", 1 << 40, None).is_ok());
        let small = signals_bytes(&m, 1_000, 100, 20);
        let long = signals_bytes(&m, 1_000_000_000, 100, 20);
        assert!(
            long - small >= 999_000_000 * 8 * 2,
            "codes: 8 channels × i16"
        );
        assert!(signals_bytes(&m, 1_000, 200_000, 20) > small);
        let e = check_signals("signals", 5 << 30, Some(1 << 30)).unwrap_err();
        assert!(e.contains("5120 MB") && e.contains("--rate"), "{e}");
    }
}
