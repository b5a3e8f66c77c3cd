//! The reason a verdict gives when a scale on some transducers explains
//! the machine-level check ([`super::find`]): where, how large, what passes
//! too, what to check.

use super::{Kind, UnitScale};
use crate::diagnose::trust::MachineCheck;

/// The reason of a machine-level check that a scale on some transducers
/// explains: `final_gap` (the final model's; `None`: it could not be
/// re-simulated) against its `floor` as `check` judged it [text].
pub fn reason(u: &UnitScale, final_gap: Option<f64>, floor: f64, check: MachineCheck) -> String {
    let limit = match check {
        MachineCheck::Disagrees { limit } | MachineCheck::CannotJudge { limit } => limit,
        MachineCheck::Agrees => MachineCheck::limit(floor),
    };
    let kind = u.columns();
    let s = u.factor;
    let (readings, transducers) = match &u.bearing {
        Some(b) if u.channel.is_some() => (
            format!("{b}'s `{kind}` readings"),
            format!("the `{kind}` transducer of {b}"),
        ),
        Some(b) => (
            format!("{b}'s `{kind}` readings"),
            format!("the `{kind}` transducers of {b}"),
        ),
        None => (
            format!("every `{kind}` reading"),
            format!("every `{kind}` transducer"),
        ),
    };
    let at = u
        .bearing
        .as_deref()
        .map_or(String::new(), |b| format!(" at {b}"));
    let pedestals = match u.kind {
        _ if u.channel.is_some() => {
            "the pedestals refitted to the readings so corrected".to_string()
        }
        Kind::Rel => format!("pedestals{at} k, m, c and runouts ÷ {s:.3}"),
        Kind::Ped => format!("pedestals{at} k, m, c × {s:.3}"),
    };
    let nearest = match &u.nearest {
        Some(n) => format!(": the common unit factor {n}"),
        None => ", near no common unit factor".to_string(),
    };
    let [lo, hi] = u.factor_interval;
    let off = if u.channel.is_some() {
        format!("the pedestal{at} identified from these readings is wrong (not by one factor)")
    } else {
        "the pedestals identified from these readings are off by that factor".to_string()
    };
    let scale = format!(
        "with {readings} divided by {s:.4} ± {:.2} % (gap {:.4}, noise floor {:.4}; {pedestals}; factors {lo:.4} to {hi:.4} pass){nearest}",
        100.0 * u.log_sd,
        u.gap,
        u.floor
    );
    let Some(final_gap) = final_gap else {
        return format!(
            "the identified model could not be re-simulated, so the machine-level check could not judge it, but the base model, which fails it as read, passes it {scale}. A unit or scale mistake on {transducers} is likely: check the `{kind}` column's units; {off}"
        );
    };
    if check == MachineCheck::Agrees && u.also_fits.is_empty() {
        // One channel at a bearing whose base model is poor, found while
        // the identified model passes the check (`find`'s `poor`).
        return format!(
            "the identified model passes the machine-level check (machine-level gap {final_gap:.4}, noise floor {floor:.4}, limit {limit:.4}), but the base model, which fails it as read, passes it too {scale}. A unit or scale mistake on {transducers} is likely: check the `{kind}` column's units; {off}"
        );
    }
    if check == MachineCheck::Agrees {
        return format!(
            "the machine-level check cannot tell the named {} from a unit or scale mistake on {transducers}: the identified model passes it (machine-level gap {final_gap:.4}, noise floor {floor:.4}, limit {limit:.4}), and so does the base model {scale}. Check the units of {transducers} (an import's unit or peak convention); neither reading is trusted",
            u.also_fits.join(", ")
        );
    }
    let others = if u.also_fits.is_empty() {
        String::new()
    } else {
        format!(" (these pass too: {})", u.also_fits.join("; "))
    };
    let tables = match &u.bearing {
        Some(b) => format!("{b}'s bearing table"),
        None => "every bearing table".to_string(),
    };
    let (likely, twin) = match &u.table {
        Some(t) if t.passes => (
            format!(
                "The machine-level check cannot tell a unit or scale mistake on {transducers} from {tables} {:.4} times the file's: check the `{kind}` columns' units and the table; neither reading is trusted, and the pedestals{at} identified from these readings are off by one factor or the other",
                t.factor
            ),
            format!(
                ", and so does the base model with {tables} × {:.4} (stiffness and damping, the pedestals{at} with it; gap {:.4}, noise floor {:.4})",
                t.factor, t.gap, t.floor
            ),
        ),
        Some(t) => (
            format!(
                "A unit or scale mistake on {transducers} is likely (an import's unit or peak convention; {tables} scaled instead, the twin reading at the pedestal level, leaves at best gap {:.4} at × {:.4}, above the limit {:.4} of its noise floor {:.4}): check the `{kind}` columns' units; {off}",
                t.gap,
                t.factor,
                MachineCheck::limit(t.floor),
                t.floor
            ),
            String::new(),
        ),
        None => (
            format!(
                "A unit or scale mistake on {transducers} is likely (an import's unit or peak convention): check the `{kind}` columns' units; {off}"
            ),
            String::new(),
        ),
    };
    let (as_read, but) = if matches!(check, MachineCheck::CannotJudge { .. }) {
        (
            "the machine-level check cannot judge the identified model (its limit is too wide: ",
            "the base model passes it",
        )
    } else {
        (
            "the machine re-simulated with the identified model does not reproduce the measurements (",
            "it does",
        )
    };
    format!(
        "{as_read}machine-level gap {final_gap:.4}, noise floor {floor:.4}, limit {limit:.4}), but {but} {scale}{others}{twin}. {likely}"
    )
}
