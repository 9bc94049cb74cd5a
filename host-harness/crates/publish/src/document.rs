//! What makes `flinch report`'s page a document to file: the date and time it was written, the
//! exact command, a footer on every printed page (tool version, the scene's SHA-256, the command,
//! "page k of N" through CSS `@page` margin boxes, which Chromium prints), inline code instead of
//! raw Markdown backticks, and for a body-region scene the ISO/TS 15066 table.

use flinch_model::body::BodyTarget;
use flinch_model::scene::{Decoupler, Scene, TargetKind};
use flinch_sim::Summary;
use std::fmt::Write;

/// HTML-escaped text (the page's own `html::esc`; not imported, so the two files import in one
/// direction only: `cargo xtask structure` refuses circles).
fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

/// UTC date and time `YYYY-MM-DD HH:MM:SS UTC` of Unix time `secs` (civil from days, H. Hinnant).
pub fn utc(secs: i64) -> String {
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC", rem / 3600, rem % 3600 / 60, rem % 60)
}

/// When the page was written: `SOURCE_DATE_EPOCH` (reproducible builds) or now.
pub fn written_at() -> String {
    let secs = std::env::var("SOURCE_DATE_EPOCH").ok().and_then(|s| s.trim().parse::<i64>().ok()).unwrap_or_else(|| std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs() as i64));
    utc(secs)
}

/// The command as typed (each argument quoted when it holds a space or a quote).
pub fn command_line() -> String {
    std::env::args()
        .enumerate()
        .map(|(i, a)| {
            let a = if i == 0 { std::path::Path::new(&a).file_name().map_or(a.clone(), |f| f.to_string_lossy().into_owned()) } else { a };
            if a.is_empty() || a.contains([' ', '"', '\'', '{', '}', ';', '$']) { format!("'{}'", a.replace('\'', "'\\''")) } else { a }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A CSS string literal.
fn css_string(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' | '\\' => {
                o.push('\\');
                o.push(c);
            }
            '\n' => o.push(' '),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// The printed page's footer: version, SHA-256 (first 16 hex digits), the command and the page
/// number on every page.
pub fn footer_css(version: &str, sha256: &str, command: &str) -> String {
    let cmd: String = if command.chars().count() > 110 { command.chars().take(107).collect::<String>() + "..." } else { command.to_string() };
    let left = css_string(&format!("flinch {version} | scene SHA-256 {} | {cmd}", &sha256[..16.min(sha256.len())]));
    format!(
        "@page {{ @bottom-left {{ content: {left}; font-size: 8pt; color: #444; font-family: 'DejaVu Sans', Arial, sans-serif; }} @bottom-right {{ content: \"page \" counter(page) \" of \" counter(pages); font-size: 8pt; color: #444; font-family: 'DejaVu Sans', Arial, sans-serif; }} }}"
    )
}

/// Escaped text with `code` spans (Markdown's backticks) as `<code>`: no raw Markdown on the page.
pub fn prose(s: &str) -> String {
    let mut out = String::new();
    for (i, part) in s.split('`').enumerate() {
        // An odd count of backticks leaves the last part as text.
        if i % 2 == 1 && s.matches('`').count() >= i + 1 {
            let _ = write!(out, "<code>{}</code>", esc(part));
        } else {
            out.push_str(&esc(part));
        }
    }
    out
}

/// True when a summary field applies to this run: the `body_*` fields only on a body-region scene.
pub fn applies(field: &str, s: &Summary) -> bool {
    !field.starts_with("body_") || s.body_region.is_some()
}

/// The ISO/TS 15066 table of a body-region scene: the limits, this run's peak force and pressure
/// with the module, and the Annex A closed-form speeds (module: m_R = m_t; rigid tool: m_R = m_r +
/// m_t) against the simulated V_c. `None` for other targets.
pub fn iso_ts_15066(sc: &Scene, s: &Summary) -> Option<String> {
    let TargetKind::BodyRegion(b) = sc.target.kind else { return None };
    let mut t = String::new();
    let contact = if b.contact == flinch_model::body::BodyContact::QuasiStatic { "quasi-static (clamped): Table A.2" } else { "transient (free): 2 x Table A.2" };
    let _ = writeln!(t, "<h2>ISO/TS 15066 body region</h2><p>{} ({}), contact area {:.2} cm^2, m_H {} kg, k {} N/mm (Table A.3, as commonly reproduced: check against the licensed text).</p>", esc(b.region.label), contact, b.area_m2 * 1e4, b.mass_kg, b.stiffness_n_per_m * 1e-3);
    let _ = writeln!(t, "<table id=\"iso-ts-15066\"><tr><th>what</th><th>speed, m/s</th><th>peak force, N</th><th>force limit, N</th><th>force margin, N</th><th>peak pressure, N/cm^2</th><th>pressure limit, N/cm^2</th><th>pressure margin, N/cm^2</th><th>limits</th></tr>");
    let opt = |x: Option<f64>, k: f64| x.map_or("-".to_string(), |v| format!("{:.1}", v * k));
    let module = match sc.decoupler {
        Decoupler::Rigid => "rigid tool (simulated)",
        _ => "module (simulated)",
    };
    let _ = writeln!(
        t,
        "<tr><td>{module}</td><td class=\"num\">{:.3}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
        sc.motion.speed,
        opt(s.body_peak_force_n, 1.0),
        opt(s.body_force_limit_n, 1.0),
        opt(s.body_force_margin_n, 1.0),
        opt(s.body_peak_pressure_pa, 1e-4),
        opt(s.body_pressure_limit_pa, 1e-4),
        opt(s.body_pressure_margin_pa, 1e-4),
        match s.body_limits_pass { Some(true) => "hold", Some(false) => "EXCEEDED", None => "-" }
    );
    let closed = |label: &str, m: f64, b: &BodyTarget| {
        let v = b.closed_form_speed(m);
        let f = b.closed_form_force();
        format!(
            "<tr><td>{label}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td></td><td></td><td class=\"num\">{}</td><td></td><td>{}</td></tr>",
            v.map_or("not permitted".to_string(), |v| format!("{v:.3}")),
            f.map_or("-".to_string(), |(f, _)| format!("{f:.1}")),
            opt(s.body_force_limit_n, 1.0),
            opt(s.body_pressure_limit_pa, 1e-4),
            f.map_or(String::new(), |(_, why)| format!("F at {why}")),
        )
    };
    let m_t = sc.tool.mass;
    let _ = writeln!(t, "{}", closed(&format!("closed form, module (m_R = m_t = {m_t} kg)"), m_t, &b));
    let m_r = sc.robot.map_or(f64::INFINITY, |r| r.mass + m_t);
    let _ = writeln!(t, "{}", closed(&format!("closed form, rigid tool (m_R = {})", if m_r.is_finite() { format!("m_r + m_t = {m_r} kg") } else { "infinite".into() }), m_r, &b));
    let _ = writeln!(t, "</table><p>Closed form: ISO/TS 15066 Annex A, v = F / sqrt(mu k), the impact energy only (no driving on until the stop, no stroke). The largest simulated speeds per tool: <code>flinch design SCENE --body-region {}</code>.</p>", b.region.name);
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_and_prose() {
        assert_eq!(utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc(1_795_000_000), "2026-11-18 11:06:40 UTC");
        assert_eq!(prose("run `flinch check` <now>"), "run <code>flinch check</code> &lt;now&gt;");
        assert!(footer_css("0.1.0", "ab".repeat(32).as_str(), "flinch report x").contains("counter(pages)"));
    }
}
