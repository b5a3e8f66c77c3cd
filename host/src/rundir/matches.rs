//! Whether a machine file describes the machine a run directory was
//! measured on: the same bearings by name (a file of another machine, or
//! one with an extra or renamed bearing, would be simulated against
//! readings it never made).

use super::RunDir;
use crate::sim::machine::Machine;
use std::collections::BTreeSet;
use std::path::Path;

/// Checks that `machine` (read from `file`) has exactly the bearings of
/// `run` (its measurements and bearing coefficients); the error names the
/// bearings each side lacks.
pub fn check_machine(run: &RunDir, machine: &Machine, file: &Path) -> anyhow::Result<()> {
    let in_run: BTreeSet<&str> = run
        .measurements
        .iter()
        .map(|m| m.bearing.as_str())
        .chain(run.bearings.iter().map(|b| b.bearing.as_str()))
        .collect();
    let in_file: BTreeSet<&str> = machine.bearings.iter().map(|b| b.name.as_str()).collect();
    if in_run == in_file {
        return Ok(());
    }
    let list = |s: &BTreeSet<&str>| {
        s.iter()
            .map(|n| format!("`{}`", n.escape_debug()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let only_file: BTreeSet<&str> = in_file.difference(&in_run).copied().collect();
    let only_run: BTreeSet<&str> = in_run.difference(&in_file).copied().collect();
    let mut parts = Vec::new();
    if !only_file.is_empty() {
        parts.push(format!("{} not in the run", list(&only_file)));
    }
    if !only_run.is_empty() {
        parts.push(format!("the run's {} not in the file", list(&only_run)));
    }
    anyhow::bail!(
        "--machine {}: machine `{}` has bearings {} ({}) but the run has {} ({}): {}; give the machine file of the machine this run was measured on",
        file.display(),
        machine.name.escape_debug(),
        list(&in_file),
        in_file.len(),
        list(&in_run),
        in_run.len(),
        parts.join("; ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn another_machines_file_is_refused_naming_the_bearings() {
        let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/");
        let paper =
            Machine::from_toml_path(Path::new(&format!("{root}feng-hahn-1997.toml"))).unwrap();
        let run =
            crate::sim::unbalance_response(&paper, &[10.0, 20.0], &crate::sim::EffectSet::none())
                .unwrap()
                .to_run_dir(None)
                .unwrap();
        check_machine(&run, &paper, Path::new("m.toml")).unwrap();
        let mut extra = paper.clone();
        let mut third = extra.bearings[0].clone();
        third.name = "third".into();
        extra.bearings.push(third);
        let e = check_machine(&run, &extra, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`third` not in the run") && e.contains("(3)"),
            "{e}"
        );
        let mut renamed = paper.clone();
        renamed.bearings[1].name = "NDE".into();
        let e = check_machine(&run, &renamed, Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`NDE` not in the run") && e.contains("the run's `right` not in the file"),
            "{e}"
        );
    }
}
