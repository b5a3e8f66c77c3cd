//! The report's HTML: one page, inline SVG figures, a print style sheet,
//! no script and nothing fetched. The identification is read through its
//! JSON form (the contract of `identify --json`: `noise`, `warnings`,
//! `modal`), so the page shows what `identify --json` shows.

use super::Contents;
use crate::field::plot::{figures, polar_svg};
use crate::plots::SpeedUnit;
use anyhow::Result;
use serde_json::Value;
use std::fmt::Write as _;

/// HTML-escapes text.
pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

const STYLE: &str = "
body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;max-width:1250px;margin:1.5em auto;padding:0 1em;color:#111;line-height:1.35}
h1{font-size:1.6em;margin-bottom:.2em} h2{border-bottom:1px solid #999;margin-top:1.8em} h3{margin-bottom:.3em}
table{border-collapse:collapse;margin:.5em 0 1em} th,td{border:1px solid #bbb;padding:.2em .55em;text-align:right;vertical-align:top}
th{background:#eee} .l{text-align:left}
pre{background:#f5f5f5;padding:.6em;overflow-x:auto;font-size:.82em}
figure{margin:1.2em 0;break-inside:avoid;page-break-inside:avoid}
figure svg{max-width:100%;height:auto;display:block;border:1px solid #ddd}
figcaption{font-size:.9em;color:#333;margin-top:.3em}
.polars{display:flex;flex-wrap:wrap;gap:.5em} .polars figure{width:32%;min-width:300px;margin:.3em 0}
.untrusted{color:#b00000;font-weight:bold} .ok{color:#006400;font-weight:bold} .muted{color:#555}
@media print{body{max-width:none;margin:0;font-size:10pt} h2{break-after:avoid;page-break-after:avoid}
 pre{white-space:pre-wrap} .polars figure{width:48%} a{color:inherit;text-decoration:none}}
";

/// A number with `digits` significant digits.
fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "–".into()
        } else {
            "∞".into()
        };
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&mag) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

/// A JSON number (`null`: not a number).
fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Figure counter and the `<figure>` markup.
struct Figures {
    n: usize,
}

impl Figures {
    fn figure(&mut self, out: &mut String, svg: &str, caption: &str) {
        self.n += 1;
        let _ = writeln!(
            out,
            "<figure id=\"fig-{}\" class=\"plot\">{svg}<figcaption>Figure {}. {}</figcaption></figure>",
            self.n,
            self.n,
            esc(caption)
        );
    }
}

/// "What was measured": files, bearings and speeds, transducers, noise.
fn measured(c: &Contents<'_>, json: &Value, out: &mut String) {
    out.push_str("<h2 id=\"measured\">What was measured</h2>\n<h3>Source files</h3>\n<table><tr><th class=\"l\">file</th><th>bytes</th></tr>\n");
    let mut files: Vec<(String, u64)> = std::fs::read_dir(c.dir)
        .map(|rd| {
            rd.flatten()
                .filter(|e| e.path().is_file())
                .map(|e| {
                    let size = e.metadata().map(|m| m.len()).unwrap_or(0);
                    (e.file_name().to_string_lossy().to_string(), size)
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    for (name, size) in &files {
        let _ = writeln!(
            out,
            "<tr><td class=\"l\">{}</td><td>{size}</td></tr>",
            esc(&c.dir.join(name).display().to_string())
        );
    }
    out.push_str("</table>\n<h3>Bearings and speeds</h3>\n<table><tr><th class=\"l\">bearing</th><th>speeds</th><th>lowest [Hz]</th><th>highest [Hz]</th><th>lowest [rpm]</th><th>highest [rpm]</th></tr>\n");
    for b in c.run.measured_bearings() {
        let speeds: Vec<f64> = c
            .run
            .measurements
            .iter()
            .filter(|m| m.bearing == b)
            .map(|m| m.speed_hz)
            .collect();
        let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let _ = writeln!(
            out,
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.0}</td><td>{:.0}</td></tr>",
            esc(b),
            speeds.len(),
            sig(lo, 4),
            sig(hi, 4),
            lo * 60.0,
            hi * 60.0
        );
    }
    out.push_str("</table>\n<h3>Transducers</h3>\n");
    if c.transducers.is_empty() {
        out.push_str("<p class=\"muted\">No transducers.csv: the run holds resolved y/z phasors only (simulated, or written by hand).</p>\n");
    } else {
        out.push_str("<table><tr><th class=\"l\">bearing</th><th class=\"l\">measures</th><th>angle [deg from +y towards +z]</th></tr>\n");
        for t in c.transducers {
            let _ = writeln!(
                out,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td></tr>",
                esc(&t.bearing),
                match t.quantity.name() {
                    "rel" => "rel: rotor relative to pedestal",
                    _ => "ped: pedestal, absolute",
                },
                t.angle_deg
            );
        }
        out.push_str("</table>\n");
    }
    out.push_str("<h3>Noise</h3>\n<table><tr><th class=\"l\">bearing</th><th class=\"l\">source</th><th>rel_y sd [µm]</th><th>rel_z sd [µm]</th><th>ped_y sd [µm]</th><th>ped_z sd [µm]</th><th>χ²/dof</th><th>p</th></tr>\n");
    if let Some(noise) = json.get("noise").and_then(Value::as_object) {
        for (b, n) in noise {
            let sd = |ch: &str| sig(num(&n["sd"][ch]) * 1e6, 2);
            let chi2 = num(&n["chi2"]) / num(&n["dof"]).max(1.0);
            let _ = writeln!(
                out,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(b),
                esc(n["source"].as_str().unwrap_or("?")),
                if n["scale_estimated"].as_bool() == Some(true) {
                    " (level from χ²)"
                } else {
                    ""
                },
                sd("rel_y"),
                sd("rel_z"),
                sd("ped_y"),
                sd("ped_z"),
                sig(chi2, 3),
                sig(num(&n["p_value"]), 2)
            );
        }
    }
    out.push_str("</table>\n");
}

/// The identified table, the modal view and the trust flags with reasons.
fn identified(c: &Contents<'_>, json: &Value, out: &mut String) {
    out.push_str("<h2 id=\"identified\">Identified pedestals</h2>\n<pre>");
    out.push_str(&esc(&crate::identify::cli::table(
        c.identification,
        c.run.truth.as_ref(),
    )));
    out.push_str(&esc(&crate::identify::on_base::describe(
        &c.identification.bases,
    )));
    out.push_str(
        "</pre>\n<h3>Modal view (natural frequency and damping ratio per direction)</h3>\n",
    );
    let pedestals = json["pedestals"].as_array().cloned().unwrap_or_default();
    if pedestals.iter().any(|p| p.get("modal").is_some()) {
        out.push_str("<table><tr><th class=\"l\">bearing</th><th class=\"l\">dir.</th><th>f_n [Hz]</th><th>f_n [rpm]</th><th>ζ [%]</th></tr>\n");
        for p in &pedestals {
            for d in ["y", "z"] {
                let m = &p["modal"][d];
                if m.is_null() {
                    continue;
                }
                let (f, sf) = (num(&m["f_n_hz"]), num(&m["f_n_std_err"]));
                let (z, sz) = (num(&m["zeta"]), num(&m["zeta_std_err"]));
                let _ = writeln!(
                    out,
                    "<tr><td class=\"l\">{}</td><td class=\"l\">{d}</td><td>{} ± {}</td><td>{} ± {}</td><td>{} ± {}</td></tr>",
                    esc(p["bearing"].as_str().unwrap_or("?")),
                    sig(f, 5),
                    sig(sf, 2),
                    sig(f * 60.0, 5),
                    sig(sf * 60.0, 2),
                    sig(100.0 * z, 3),
                    sig(100.0 * sz, 2)
                );
            }
        }
        out.push_str("</table>\n");
    } else {
        out.push_str("<p class=\"muted\">This identification carries no modal view (`modal` in identify's JSON).</p>\n");
    }
    out.push_str("<h3>Trust</h3>\n<table><tr><th class=\"l\">bearing</th><th class=\"l\">fit</th><th class=\"l\">reasons and remarks</th></tr>\n");
    for p in &pedestals {
        let trusted = p["trusted"].as_bool() == Some(true);
        let mut reasons = String::new();
        for w in p["warnings"].as_array().into_iter().flatten() {
            let _ = write!(
                reasons,
                "<li><code>{}</code>: {}</li>",
                esc(w["kind"].as_str().unwrap_or("?")),
                esc(w["message"].as_str().unwrap_or(""))
            );
        }
        let _ = writeln!(
            out,
            "<tr><td class=\"l\">{}</td><td class=\"l\"><span class=\"{}\">{}</span></td><td class=\"l\">{}</td></tr>",
            esc(p["bearing"].as_str().unwrap_or("?")),
            if trusted { "ok" } else { "untrusted" },
            if trusted { "ok" } else { "UNTRUSTED" },
            if reasons.is_empty() {
                "none".to_string()
            } else {
                format!("<ul>{reasons}</ul>")
            }
        );
    }
    out.push_str("</table>\n");
}

/// The whole page.
pub fn render(c: &Contents<'_>) -> Result<String> {
    let json = serde_json::to_value(c.identification)?;
    let mut out = String::new();
    let title = format!("Plinth report: {}", c.dir.display());
    let _ = write!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n<p class=\"muted\">Pedestal identification after Feng &amp; Hahn (1997): plinth {}, <code>{}</code></p>\n",
        esc(&title),
        esc(&title),
        env!("CARGO_PKG_VERSION"),
        esc(&c.command)
    );
    out.push_str("<p><a href=\"#measured\">What was measured</a> · <a href=\"#identified\">Identified pedestals</a> · <a href=\"#fitted\">Measured vs fitted</a> · <a href=\"#bode\">Bode and polar</a>");
    if c.diagnosis.is_some() {
        out.push_str(" · <a href=\"#diagnosis\">Diagnosis</a>");
    }
    out.push_str(" · <a href=\"#made\">How this report was made</a></p>\n");
    measured(c, &json, &mut out);
    identified(c, &json, &mut out);

    let mut figs = Figures { n: 0 };
    let style = c.options.style;
    out.push_str("<h2 id=\"fitted\">Measured vs fitted</h2>\n<p>Each pedestal's measured dynamic stiffness F/X (F the force its bearing transmits, from the bearing coefficients and the rotor-relative motion; X the pedestal's absolute motion) against the fitted k − Ω²m + iΩc with its ±1σ band, and the residual of eq. 3 at each speed: where the model misses.</p>\n");
    let (inputs, skipped) = super::fitted::stiffness_inputs(c.run, c.identification)?;
    for s in &skipped {
        let _ = writeln!(out, "<p class=\"muted\">{}</p>", esc(s));
    }
    for input in inputs {
        let bearing = input.bearing.clone();
        let svg = super::fitted::figure(input, style).to_svg()?;
        figs.figure(
            &mut out,
            &svg,
            &format!("Pedestal {bearing}: measured F/X (markers), the fit (line) and its ±1σ band; residual below."),
        );
    }

    out.push_str("<h2 id=\"bode\">Bode and polar</h2>\n");
    let (bode, loci) = figures(c.run, c.transducers, style);
    for f in &bode {
        let svg = f.to_svg()?;
        figs.figure(&mut out, &svg, &f.title);
    }
    let rotation = match c.options.rotation {
        crate::field::angle::Rotation::Ccw => "counter-clockwise",
        crate::field::angle::Rotation::Cw => "clockwise",
    };
    let _ = writeln!(
        out,
        "<p>Polar plots: amplitude as radius, phase lag measured against {rotation} rotation from 0° at {}; ■ start, ▲ end of the run.</p>\n<div class=\"polars\">",
        if c.options.zero_at_transducer {
            "each transducer"
        } else {
            "the top"
        }
    );
    for l in &loci {
        let svg = polar_svg(l, &c.options)?;
        figs.figure(&mut out, &svg, &format!("Polar: {}", l.name));
    }
    out.push_str("</div>\n");

    if let Some(outcome) = c.diagnosis {
        out.push_str("<h2 id=\"diagnosis\">Diagnosis</h2>\n<pre>");
        let modal = crate::diagnose::cli::modal_views(outcome);
        out.push_str(&esc(&outcome.diagnosis.to_text_with(&modal)));
        out.push_str("</pre>\n");
        for (stem, fig) in crate::diagnose::plots::pedestal_figures(outcome) {
            let svg = fig.to_svg()?;
            figs.figure(&mut out, &svg, &format!("{stem}: {}", fig.title));
        }
    }

    let _ = write!(
        out,
        "<h2 id=\"made\">How this report was made</h2>\n<table><tr><th class=\"l\">command</th><td class=\"l\"><code>{}</code></td></tr>\n<tr><th class=\"l\">version</th><td class=\"l\">plinth {}</td></tr>\n<tr><th class=\"l\">identification</th><td class=\"l\">as <code>{}</code> (estimator {}, equations {}, model {})</td></tr>\n<tr><th class=\"l\">speed unit</th><td class=\"l\">{}</td></tr>\n<tr><th class=\"l\">figures</th><td class=\"l\">{}</td></tr></table>\n</body>\n</html>\n",
        esc(&c.command),
        env!("CARGO_PKG_VERSION"),
        esc(&c.identify_command),
        esc(&c.identification.estimator),
        esc(&c.identification.equations),
        esc(&c.identification.model.join(",")),
        match style.speed_unit {
            SpeedUnit::Hz => "Hz",
            SpeedUnit::Rpm => "rpm",
        },
        figs.n
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping() {
        assert_eq!(esc("a<b & \"c\"'"), "a&lt;b &amp; &quot;c&quot;&#39;");
    }
}
