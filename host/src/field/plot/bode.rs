//! The Bode figure of one bearing and quantity.

use super::Locus;
use crate::field::transducer::Quantity;
use crate::plots::{
    PhaseStyle, PhasorFigure, PhasorPanel, PhasorSeries, PhasorView, Quantity as PlotQuantity,
    Rows, Style,
};

/// The Bode figure of one bearing and quantity: resolved y/z in one panel,
/// the transducers' own readings in one panel per unit.
pub(super) fn bode_figure(
    bearing: &str,
    q: Quantity,
    loci: &[&Locus],
    style: Style,
) -> PhasorFigure {
    // Series named by direction or angle only (the panel names the
    // bearing): each its own colour.
    let prefix = format!("{bearing} {} ", q.name());
    let short = |l: &Locus| l.name.strip_prefix(&prefix).unwrap_or(&l.name).to_string();
    let resolved: Vec<PhasorSeries> = loci
        .iter()
        .filter(|l| !l.transducer)
        .map(|l| PhasorSeries::line(short(l), l.signal()))
        .collect();
    let mut panels = vec![PhasorPanel::new(
        format!("{bearing} {}: resolved y, z", q.name()),
        resolved,
    )];
    let mut units: Vec<PlotQuantity> = Vec::new();
    for l in loci.iter().filter(|l| l.transducer) {
        if !units.contains(&l.unit) {
            units.push(l.unit);
        }
    }
    for u in units {
        let series: Vec<PhasorSeries> = loci
            .iter()
            .filter(|l| l.transducer && l.unit == u)
            .map(|l| PhasorSeries::line(short(l), l.signal()))
            .collect();
        panels.push(PhasorPanel {
            title: format!("{bearing} {}: transducers", q.name()),
            series,
            quantity: Some(u),
        });
    }
    PhasorFigure {
        title: format!(
            "Bode: bearing {bearing}, {} (1X amplitude and phase lag)",
            q.name()
        ),
        quantity: PlotQuantity::DisplacementMicrons,
        view: PhasorView::Engineer(PhaseStyle::Wrapped),
        rows: Rows::Both,
        panels,
        style,
    }
}
