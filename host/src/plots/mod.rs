//! Plots an engineer puts in a report: 1X amplitude and phase against rotor
//! speed, the phase difference between a pedestal's response and the force
//! transmitted to it, and measured-versus-predicted overlays.
//!
//! Every figure is written twice, as PNG (bitmap) and SVG, from the same
//! drawing code. Text is laid out with a bundled font (DejaVu Sans, Bitstream
//! Vera licence, `host/assets/fonts/`) registered with plotters' `ab_glyph`
//! backend, so figures render identically on a machine without any system
//! fonts (CI containers, a newcomer's fresh laptop).
//!
//! Phasor conventions (formats.md): a signal q(t) has phasor Q when
//! q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor. The engineer's view
//! ([`PhasorView::Engineer`]) shows what field instruments print: the
//! peak-to-peak amplitude 2|Q| and the phase *lag* −arg Q in degrees, either
//! wrapped to [0, 360) or unwrapped along the speed axis (continuous, starting
//! in [0, 360) at the lowest speed). The raw views show the complex number
//! itself: real and imaginary parts, or |Q| and the angle arg Q (a lead,
//! wrapped to (−180, 180]).
//!
//! Files: this one (fonts, the figure types, writing both formats),
//! `phase` (phase conventions), `chart` (drawing), `axis` (ticks),
//! `legend` (legends beside the data), `stiffness` (a pedestal's measured
//! dynamic stiffness against its fitted model), `labels` (speed labels on a
//! locus that never overlap).

/// `write` (`<stem>.png` and `<stem>.svg`) and `to_svg` (an SVG document in
/// memory) of a figure type that has `size()` [px] and `draw()`: the one
/// definition of a figure's output for every figure type (inherent methods,
/// so callers need no trait in scope).
macro_rules! figure_output {
    ($figure:ty) => {
        impl $figure {
            /// Writes `<stem>.png` and `<stem>.svg`; returns both paths.
            pub fn write(&self, stem: &std::path::Path) -> anyhow::Result<[std::path::PathBuf; 2]> {
                $crate::plots::write_both(
                    stem,
                    self.size(),
                    |root| self.draw(root),
                    |root| self.draw(root),
                )
            }

            /// The figure as an SVG document in memory (for an HTML report).
            pub fn to_svg(&self) -> anyhow::Result<String> {
                $crate::plots::svg_string(self.size(), |root| self.draw(root))
            }
        }
    };
}

mod axis;
mod chart;
mod figures;
pub mod labels;
mod legend;
mod phase;
pub mod stiffness;

use axis::*;
pub use chart::*;
pub use figures::*;
use legend::*;
pub use phase::*;

use anyhow::{anyhow, Context, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The bundled sans-serif font (DejaVu Sans 2.37, Bitstream Vera licence).
static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Font family name every figure uses; registered once with [`ensure_fonts`].
const FONT: &str = "sans-serif";

/// Registers the bundled font with plotters (idempotent, thread-safe).
///
/// Called by every drawing function; public so callers that draw their own
/// plotters charts get the same font.
pub fn ensure_fonts() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, DEJAVU_SANS).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Bold, DEJAVU_SANS).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(anyhow!(
            "the bundled font DejaVuSans.ttf could not be parsed"
        ))
    }
}

/// What a phasor's magnitude measures, for axis labels and scaling.
///
/// Displacements are shown peak-to-peak (the proximity-probe habit);
/// velocities and accelerations zero-to-peak (`mm/s pk`, `in/s pk`, `g pk`,
/// the pick-ups' own habit). The phasors of a velocity or acceleration
/// series are the pick-up's own signal (iΩ·X or −Ω²·X, SI units), not a
/// displacement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Displacement: phasors in m, plotted in µm pk-pk.
    DisplacementMicrons,
    /// Displacement: phasors in m, plotted in mil pk-pk (1 mil = 25.4 µm).
    DisplacementMils,
    /// Velocity: phasors in m/s, plotted in mm/s pk.
    VelocityMmPerSecond,
    /// Velocity: phasors in m/s, plotted in in/s pk.
    VelocityInchPerSecond,
    /// Acceleration: phasors in m/s², plotted in g pk (9.80665 m/s²).
    AccelerationG,
    /// Force: phasors in N, plotted in N.
    ForceNewtons,
    /// Force: phasors in N, plotted in kN.
    ForceKilonewtons,
}

impl Quantity {
    /// Factor from the phasor's SI unit to the plotted unit.
    pub fn scale(self) -> f64 {
        match self {
            Quantity::DisplacementMicrons => 1e6,
            Quantity::DisplacementMils => 1.0 / 25.4e-6,
            Quantity::VelocityMmPerSecond => 1e3,
            Quantity::VelocityInchPerSecond => 1.0 / 0.0254,
            Quantity::AccelerationG => 1.0 / 9.80665,
            Quantity::ForceNewtons => 1.0,
            Quantity::ForceKilonewtons => 1e-3,
        }
    }

    /// Unit symbol of the plotted values.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::DisplacementMicrons => "µm",
            Quantity::DisplacementMils => "mil",
            Quantity::VelocityMmPerSecond => "mm/s",
            Quantity::VelocityInchPerSecond => "in/s",
            Quantity::AccelerationG => "g",
            Quantity::ForceNewtons => "N",
            Quantity::ForceKilonewtons => "kN",
        }
    }

    /// True when the engineer's amplitude is peak-to-peak (displacement),
    /// false when zero-to-peak (velocity, acceleration, force).
    pub fn peak_to_peak(self) -> bool {
        matches!(
            self,
            Quantity::DisplacementMicrons | Quantity::DisplacementMils
        )
    }

    /// How many times the signal is differentiated from displacement: 0, 1
    /// (velocity) or 2 (acceleration); `None` for a force.
    pub fn derivative_order(self) -> Option<u32> {
        match self {
            Quantity::DisplacementMicrons | Quantity::DisplacementMils => Some(0),
            Quantity::VelocityMmPerSecond | Quantity::VelocityInchPerSecond => Some(1),
            Quantity::AccelerationG => Some(2),
            Quantity::ForceNewtons | Quantity::ForceKilonewtons => None,
        }
    }

    /// The pick-up's own phasor of a displacement phasor `x` [m] at
    /// `speed_hz`: x, iΩx [m/s] or −Ω²x [m/s²] (a force is returned as is).
    pub fn from_displacement(self, x: Complex<f64>, speed_hz: f64) -> Complex<f64> {
        let iw = Complex::new(0.0, std::f64::consts::TAU * speed_hz);
        match self.derivative_order() {
            Some(1) => iw * x,
            Some(2) => iw * iw * x,
            _ => x,
        }
    }
}

/// The unit of the speed axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum SpeedUnit {
    /// Rotor speed in Hz (revolutions per second), the run directory's unit.
    #[default]
    Hz,
    /// Rotor speed in rpm (revolutions per minute), the field's habit.
    Rpm,
}

impl SpeedUnit {
    /// Factor from Hz to this unit.
    pub fn factor(self) -> f64 {
        match self {
            SpeedUnit::Hz => 1.0,
            SpeedUnit::Rpm => 60.0,
        }
    }

    /// Unit symbol: `Hz` or `rpm`.
    pub fn symbol(self) -> &'static str {
        match self {
            SpeedUnit::Hz => "Hz",
            SpeedUnit::Rpm => "rpm",
        }
    }

    /// The speed axis' label, e.g. `Rotor speed [rpm]`.
    pub fn axis_label(self) -> String {
        format!("Rotor speed [{}]", self.symbol())
    }

    /// A speed [Hz] as text in this unit, e.g. `1500 rpm` or `25.0 Hz`.
    pub fn label(self, speed_hz: f64) -> String {
        match self {
            SpeedUnit::Hz => format!("{speed_hz:.1} Hz"),
            SpeedUnit::Rpm => format!("{:.0} rpm", speed_hz * 60.0),
        }
    }
}

/// How every figure is drawn, whatever it shows: the field's reading
/// options (`--speed-unit`, `--log-amplitude`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Style {
    /// Unit of the speed axis and speed labels.
    pub speed_unit: SpeedUnit,
    /// Amplitude rows on a logarithmic axis (decades).
    pub log_amplitude: bool,
}

/// How the phase of an engineer's plot is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhaseStyle {
    /// Phase lag −arg Q in degrees, wrapped to [0, 360); lines break at wraps.
    Wrapped,
    /// Phase lag in degrees made continuous along increasing speed, starting
    /// in [0, 360) at the lowest speed.
    Unwrapped,
}

/// Which pair of rows a phasor figure shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhasorView {
    /// Peak-to-peak amplitude 2|Q| and phase lag [deg] (field instruments).
    Engineer(PhaseStyle),
    /// Re Q and Im Q of q(t) = Re{Q·e^{iΩt}}.
    ReIm,
    /// |Q| (zero-to-peak) and arg Q [deg] in (−180, 180].
    AmplitudeAngle,
}

/// Which rows of a phasor figure are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rows {
    /// The magnitude-like row (amplitude, or Re) and the angle-like row.
    Both,
    /// Only the magnitude-like row (e.g. the paper's Figs. 3 and 7).
    First,
    /// Only the angle-like row (e.g. the paper's Figs. 4 and 8).
    Second,
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A solid line through the points.
    Line,
    /// Hollow circles at the points (measured data over a predicted line).
    Markers,
}

/// The figure options every command that draws takes (`--speed-unit`,
/// `--log-amplitude`), flattened into its arguments.
#[derive(clap::Args, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StyleArgs {
    /// Unit of the figures' speed axes and speed labels.
    #[arg(long, value_enum, default_value_t = SpeedUnit::Hz)]
    pub speed_unit: SpeedUnit,
    /// Amplitudes on a logarithmic axis (decades) in Bode figures.
    #[arg(long)]
    pub log_amplitude: bool,
}

impl StyleArgs {
    /// The figure style these options ask for.
    pub fn style(&self) -> Style {
        Style {
            speed_unit: self.speed_unit,
            log_amplitude: self.log_amplitude,
        }
    }
}

/// One named curve of 1X phasors against rotor speed.
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorSeries {
    /// Legend entry, e.g. `Ly` (left bearing, vertical).
    pub name: String,
    /// (rotor speed [Hz], phasor [SI unit of the figure's quantity]).
    pub points: Vec<(f64, Complex<f64>)>,
    /// Line or markers.
    pub mark: Mark,
}

impl PhasorSeries {
    /// A solid-line series.
    pub fn line(name: impl Into<String>, points: Vec<(f64, Complex<f64>)>) -> Self {
        Self {
            name: name.into(),
            points,
            mark: Mark::Line,
        }
    }

    /// A marker series.
    pub fn markers(name: impl Into<String>, points: Vec<(f64, Complex<f64>)>) -> Self {
        Self {
            name: name.into(),
            points,
            mark: Mark::Markers,
        }
    }
}

/// One named curve of real values against rotor speed.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarSeries {
    /// Legend entry.
    pub name: String,
    /// (rotor speed [Hz], value [unit of the panel's y axis]).
    pub points: Vec<(f64, f64)>,
    /// Line or markers.
    pub mark: Mark,
}

/// A panel (one column of a phasor figure) with its own subtitle.
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorPanel {
    /// Panel subtitle, e.g. "Rotor (relative to pedestal)".
    pub title: String,
    /// The curves in this panel.
    pub series: Vec<PhasorSeries>,
    /// What this panel's phasors measure, when not the figure's quantity
    /// (e.g. velocity pick-ups beside resolved displacements).
    pub quantity: Option<Quantity>,
}

impl PhasorPanel {
    /// A panel of the figure's quantity.
    pub fn new(title: impl Into<String>, series: Vec<PhasorSeries>) -> Self {
        Self {
            title: title.into(),
            series,
            quantity: None,
        }
    }
}

/// A figure of 1X phasors against speed: one column per panel, one or two
/// rows depending on [`Rows`].
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorFigure {
    /// Figure title.
    pub title: String,
    /// What the phasors measure (axis units).
    pub quantity: Quantity,
    /// Engineer's or raw complex view.
    pub view: PhasorView,
    /// Which rows to draw.
    pub rows: Rows,
    /// Columns of the figure.
    pub panels: Vec<PhasorPanel>,
    /// Speed unit and amplitude scale.
    pub style: Style,
}

/// A figure of real values against speed (e.g. phase differences).
#[derive(Clone, Debug, PartialEq)]
pub struct ScalarFigure {
    /// Figure title.
    pub title: String,
    /// Y-axis label with unit, e.g. "Phase difference [deg]".
    pub y_label: String,
    /// Fixed y range, or `None` to fit the data.
    pub y_range: Option<(f64, f64)>,
    /// Spacing of y tick marks, or `None` for plotters' choice.
    pub y_tick_step: Option<f64>,
    /// The curves.
    pub series: Vec<ScalarSeries>,
    /// Speed unit (the y axis is the figure's own).
    pub style: Style,
}

/// Renders a figure once to PNG and once to SVG beside each other.
pub fn write_both(
    stem: &Path,
    size: (u32, u32),
    png: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
    svg: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<()>,
) -> Result<[PathBuf; 2]> {
    // Figure names come from crate::names::file_in: never a path, and the
    // extension is appended (a `.` inside a name is not an extension).
    let name = stem.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if !crate::names::is_file_name(name) {
        anyhow::bail!(
            "figure name {:?} is not a safe file name (build it with crate::names::file_in)",
            stem.display().to_string()
        );
    }
    let png_path = stem.with_file_name(format!("{name}.png"));
    let svg_path = stem.with_file_name(format!("{name}.svg"));
    if let Some(dir) = stem.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating figure directory {}", dir.display()))?;
    }
    {
        let root = BitMapBackend::new(&png_path, size).into_drawing_area();
        png(&root).with_context(|| format!("rendering {}", png_path.display()))?;
        root.present()
            .map_err(|e| anyhow!("writing {}: {}", png_path.display(), write_cause(&e)))?;
    }
    {
        let root = SVGBackend::new(&svg_path, size).into_drawing_area();
        svg(&root).with_context(|| format!("rendering {}", svg_path.display()))?;
        root.present()
            .map_err(|e| anyhow!("writing {}: {}", svg_path.display(), write_cause(&e)))?;
    }
    Ok([png_path, svg_path])
}

/// What stopped a figure's file being written, as the operating system said
/// it ("No space left on device (os error 28)"): plotters' bitmap backend
/// shows its errors only as nested debug text
/// (`BackendError(DrawingError(ImageError(IoError(Custom { .. error: "..." }))))`),
/// so the innermost quoted message is taken from it; any other error is
/// shown as plotters says it.
fn write_cause(e: &(impl std::fmt::Display + std::fmt::Debug)) -> String {
    let debug = format!("{e:?}");
    // A custom io::Error shows `error: "..."`, an OS one `message: "..."`.
    let quoted = ["error: \"", "message: \""].iter().find_map(|key| {
        let rest = &debug[debug.rfind(key)? + key.len()..];
        rest.find('"').map(|end| &rest[..end])
    });
    match quoted {
        Some(message) if !message.is_empty() => message.to_string(),
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_write_error_says_what_the_system_said() {
        #[derive(Debug)]
        #[allow(dead_code)]
        enum Nested {
            BackendError(std::io::Error),
        }
        impl std::fmt::Display for Nested {
            fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "{self:?}")
            }
        }
        let full = Nested::BackendError(std::io::Error::other(
            "No space left on device (os error 28)",
        ));
        assert_eq!(write_cause(&full), "No space left on device (os error 28)");
        let os = Nested::BackendError(std::io::Error::from_raw_os_error(28));
        assert!(
            write_cause(&os).starts_with("No space left on device"),
            "{}",
            write_cause(&os)
        );
        let plain = std::io::Error::other("x");
        assert_eq!(write_cause(&plain), "x");
    }

    fn resonance(k: f64, m: f64, c: f64) -> Vec<(f64, Complex<f64>)> {
        (1..=200)
            .map(|i| {
                let f = i as f64;
                let w = std::f64::consts::TAU * f;
                let x = Complex::new(1e-3, 0.0) / Complex::new(k - w * w * m, w * c);
                (f, x)
            })
            .collect()
    }

    #[test]
    fn unwrap_removes_jumps() {
        let u = unwrap_deg(&[350.0, 10.0, 30.0, 300.0]);
        assert_eq!(u, vec![350.0, 370.0, 390.0, 300.0]);
    }

    #[test]
    fn phase_lag_of_a_pedestal_goes_from_0_to_180() {
        let (k, m, c): (f64, f64, f64) = (1e7, 100.0, 500.0);
        let fr = (k / m).sqrt() / std::f64::consts::TAU;
        for (f, x) in resonance(k, m, c) {
            let lag = phase_lag_deg(x, Complex::new(1e-3, 0.0));
            assert!((-1e-9..=180.0).contains(&lag), "lag {lag} at {f}");
            if f < 0.5 * fr {
                assert!(lag < 10.0);
            }
            if f > 2.0 * fr {
                assert!(lag > 170.0);
            }
        }
    }

    #[test]
    fn wrapped_phase_is_split_at_wraps() {
        let s = PhasorSeries::line(
            "x",
            vec![
                (1.0, Complex::from_polar(1.0, -350f64.to_radians())),
                (2.0, Complex::from_polar(1.0, -5f64.to_radians())),
                (3.0, Complex::from_polar(1.0, -15f64.to_radians())),
            ],
        );
        let segs = view_rows(
            &s,
            PhasorView::Engineer(PhaseStyle::Wrapped),
            1,
            Quantity::DisplacementMicrons,
            false,
        );
        assert_eq!(segs.len(), 2);
        let segs = view_rows(
            &s,
            PhasorView::Engineer(PhaseStyle::Unwrapped),
            1,
            Quantity::DisplacementMicrons,
            false,
        );
        assert_eq!(segs.len(), 1);
        assert!((segs[0][1].1 - 365.0).abs() < 1e-9);
    }

    #[test]
    fn figures_render_to_png_and_svg() {
        let dir = tempfile::tempdir().unwrap();
        let keep = std::env::var_os("PLINTH_PLOT_DIR");
        let out = keep
            .as_ref()
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| dir.path().to_path_buf());
        let a = resonance(1e7, 100.0, 0.0);
        let b = resonance(1.5e7, 80.0, 2000.0);
        let fig = PhasorFigure {
            title: "Test response".into(),
            quantity: Quantity::DisplacementMicrons,
            view: PhasorView::Engineer(PhaseStyle::Wrapped),
            rows: Rows::Both,
            panels: vec![
                PhasorPanel {
                    title: "Rotor (relative)".into(),
                    series: vec![
                        PhasorSeries::line("Ly", a.clone()),
                        PhasorSeries::line("Lz", b.clone()),
                    ],
                    quantity: None,
                },
                PhasorPanel {
                    title: "Pedestal (absolute)".into(),
                    series: vec![
                        PhasorSeries::markers(
                            "Ly measured",
                            a.iter().step_by(5).copied().collect(),
                        ),
                        PhasorSeries::line("Ly predicted", a.clone()),
                    ],
                    quantity: None,
                },
            ],
            style: Style {
                speed_unit: SpeedUnit::Rpm,
                log_amplitude: true,
            },
        };
        let [png, svg] = fig.write(&out.join("test_response")).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.contains("Rotor speed [rpm]"));
        let diff = ScalarFigure {
            title: "Phase difference".into(),
            y_label: "Lag of response behind force [deg]".into(),
            y_range: Some((-30.0, 210.0)),
            y_tick_step: Some(30.0),
            series: vec![ScalarSeries {
                name: "Ly".into(),
                points: b
                    .iter()
                    .map(|&(f, x)| (f, phase_lag_deg(x, Complex::new(1e-3, 0.0))))
                    .collect(),
                mark: Mark::Line,
            }],
            style: Style::default(),
        };
        diff.write(&out.join("test_phase_diff")).unwrap();
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(format_tick(0.0), "0");
        assert_eq!(format_tick(90.0), "90");
        assert_eq!(format_tick(2.5), "2.5");
        assert_eq!(format_tick(12.3456), "12.35");
    }
}
