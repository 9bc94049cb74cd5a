//! `flinch report SCENE --out report.html`: one self-contained, printable HTML page (issue 17 item
//! 4): the verdicts first (the run's, `check`'s budget, `design`'s safe speed, and every other
//! verdict-like field the run summary carries), then the inputs with their units and where each came
//! from (the scene file's own comments), the time history, the design curve, an optional sweep, the
//! whole run summary, and the scene text itself. The figures are the SVGs the other commands draw
//! (`run --plot`, `design --plot`, `sweep --plot`), inlined; no script, no external resource. The
//! tool's version and the SHA-256 of the scene text name exactly what the page is about.
//!
//! Exit code (docs/conventions.md): 0 when every verdict on the page is favourable, 1 when one is
//! not (the page is written either way), 2 for a scene or option that cannot be read, 3 when the
//! page cannot be written or the run fails.

use flinch_output::output::{self, Failure};
use crate::schema;
use flinch_report::{plot, stream, trace::Trace};
use flinch_model::scene::{self, Key, Ty};
use flinch_studies::sweep::{self, Template};
use flinch_model::shipped;
use flinch_sim::verdict;
use flinch_studies::{check, design};
use serde_json::Value as Json;
use sha2::{Digest, Sha256};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// `flinch report SCENE --out FILE.html [--sweep KEY=START:STOP:N ...]`.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// The scene: a TOML file, `-`, or a shipped scene's name.
    pub scene: PathBuf,
    /// The HTML file to write (`-`: standard output).
    #[arg(long, value_name = "FILE.html")]
    pub out: PathBuf,
    /// Add a sweep: KEY=START:STOP:N (once: lines; twice: a heat map of --metric), as `flinch sweep --vary`.
    #[arg(long = "sweep", value_name = "KEY=START:STOP:N")]
    pub sweep: Vec<String>,
    /// The summary field the sweep's heat map shows.
    #[arg(long, default_value = "peak_robot_force")]
    pub metric: String,
    /// Set a scene key for this run: KEY=VALUE, repeatable (VALUE is TOML; a bare word is a
    /// string), validated like the file: e.g. --set motion.speed=0.5 --set target.region=face.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = flinch_model::overrides::Set::parse)]
    pub set: Vec<flinch_model::overrides::Set>,
}

/// Hex SHA-256 of the scene text, as hashed (the bytes of the file).
pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes()).iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}

/// Escapes text for HTML.
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

/// One scene key as written, with what the contract says about it and the file's comment.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// Dotted path, `motion.speed`.
    pub key: String,
    /// The value as written.
    pub value: String,
    /// Unit from the key table (empty when none or not a number).
    pub unit: String,
    /// The key table's doc line.
    pub meaning: String,
    /// The scene file's comments on it (the line's own, and comment lines just above it).
    pub source: String,
}

/// Every key the scene text sets, in file order, with unit, meaning and the file's comments.
pub fn inputs(text: &str) -> Vec<Input> {
    let Ok(doc) = text.parse::<toml_edit::DocumentMut>() else { return Vec::new() };
    let mut out = Vec::new();
    walk(doc.as_table(), "", &mut out, "");
    out
}

fn comment(decor: Option<&toml_edit::RawString>) -> String {
    decor
        .and_then(|r| r.as_str())
        .map(|s| s.lines().filter_map(|l| l.trim().strip_prefix('#')).map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" "))
        .unwrap_or_default()
}

fn walk(t: &dyn toml_edit::TableLike, path: &str, out: &mut Vec<Input>, inherited: &str) {
    let kind = t.get("kind").and_then(|k| k.as_str()).map(str::to_string);
    // An inline table's comment is shown on its first key and referred to on the others.
    let mut inherited = inherited.to_string();
    for (k, item) in t.iter() {
        let full = if path.is_empty() { k.to_string() } else { format!("{path}.{k}") };
        // Comment lines just above a key (not at the top level: there they are the file's header,
        // shown as the scene's description).
        let above = if path.is_empty() { String::new() } else { t.key(k).map(|key| comment(key.leaf_decor().prefix())).unwrap_or_default() };
        match item {
            toml_edit::Item::Table(sub) => {
                let own = comment(sub.decor().suffix());
                walk(sub, &full, out, &join(&[&above, &own]));
            }
            toml_edit::Item::Value(toml_edit::Value::InlineTable(sub)) => {
                let own = comment(sub.decor().suffix());
                walk(sub, &full, out, &join(&[&above, &own, &inherited]));
            }
            toml_edit::Item::Value(v) => {
                let own = comment(v.decor().suffix());
                let (unit, meaning) = key_info(path, k, kind.as_deref());
                let source = join(&[&above, &own]);
                let source = match (source.is_empty(), inherited.is_empty()) {
                    (false, _) => source,
                    (true, true) => String::new(),
                    (true, false) if inherited.starts_with("see ") => inherited.clone(),
                    (true, false) => std::mem::replace(&mut inherited, format!("see {full}")),
                };
                out.push(Input { key: full, value: v.clone().decorated("", "").to_string(), unit, meaning, source });
            }
            _ => {}
        }
    }
}

fn join(parts: &[&str]) -> String {
    parts.iter().filter(|p| !p.is_empty()).copied().collect::<Vec<_>>().join("; ")
}

/// Unit and doc of `table.key` from the scene's key tables (`kind` picks the variant's table).
fn key_info(table: &str, key: &str, kind: Option<&str>) -> (String, String) {
    let found: Vec<&Key> = scene::key_tables()
        .iter()
        .filter(|t| t.path == table && (t.when.is_empty() || kind.is_none_or(|k| t.when == format!("kind = \"{k}\""))))
        .flat_map(|t| t.keys.iter())
        .filter(|k| k.name == key)
        .collect();
    match found.first() {
        Some(k) => {
            let unit = match (k.ty, table, key) {
                (Ty::Number(s), _, _) => s.unit.to_string(),
                // The stopping table's lists (their items' units are in their docs).
                (_, "motion.stopping", "speed") => "m/s".into(),
                (_, "motion.stopping", "distance") => "m".into(),
                (_, "motion.stopping", "time") => "s".into(),
                _ => String::new(),
            };
            (unit, k.doc.to_string())
        }
        None => (String::new(), String::new()),
    }
}

/// Summary fields that carry a verdict: rendered in the verdict table whatever their name's
/// origin (fields another part of Flinch adds later, body-region limits for one, appear here).
fn verdict_like(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n == "safe" || n == "failures" || n == "stroke_exhausted" || ["pass", "margin", "limit", "verdict", "region", "exceed", "stroke_left", "closest_approach"].iter().any(|w| n.contains(w))
}

/// A JSON value for a table cell.
fn cell(v: &Json) -> String {
    match v {
        Json::Null => "null".into(),
        Json::Bool(b) => if *b { "yes" } else { "no" }.into(),
        Json::Number(n) => n.as_f64().map_or(n.to_string(), |x| if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) { format!("{x:.6e}") } else { format!("{}", (x * 1e6).round() / 1e6) }),
        Json::String(s) => s.clone(),
        Json::Array(a) if a.is_empty() => "none".into(),
        Json::Array(a) if a.iter().all(|x| x.is_string()) => a.iter().filter_map(|x| x.as_str()).collect::<Vec<_>>().join("; "),
        other => other.to_string(),
    }
}

fn unit(name: &str) -> String {
    match schema::unit_of(name) {
        Some("1") | None => String::new(),
        Some(u) => u.to_string(),
    }
}

/// Draws with one of the existing plot functions (they write a file) and returns the SVG text.
fn svg(name: &str, draw: impl FnOnce(&Path) -> Result<(), String>) -> Result<String, String> {
    let dir = std::env::temp_dir().join(format!("flinch-report-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let p = dir.join(format!("{name}.svg"));
    let r = draw(&p).and_then(|_| std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display())));
    let _ = std::fs::remove_dir_all(&dir);
    let s = r?;
    // Inline: no XML declaration; the width follows the page (the viewBox keeps the drawing).
    let s = s.trim_start_matches(|c| c != '<');
    let s = if s.starts_with("<?xml") { s.split_once("?>").map_or(s, |(_, r)| r.trim_start()) } else { s };
    Ok(s.replacen("<svg ", "<svg role=\"img\" preserveAspectRatio=\"xMidYMin meet\" ", 1))
}

fn badge(ok: bool) -> &'static str {
    if ok { "<span class=\"ok\">SAFE</span>" } else { "<span class=\"bad\">NOT SAFE</span>" }
}

const CSS: &str = "
@page { size: A4; margin: 14mm 12mm; }
* { box-sizing: border-box; }
body { font-family: 'DejaVu Sans', Arial, Helvetica, sans-serif; font-size: 10.5pt; color: #111; margin: 0 auto; max-width: 190mm; padding: 8mm 0; line-height: 1.35; }
h1 { font-size: 17pt; margin: 0 0 2mm; }
h2 { font-size: 13pt; margin: 7mm 0 2mm; border-bottom: 1.5px solid #333; padding-bottom: 1mm; page-break-after: avoid; break-after: avoid; }
h3 { font-size: 11pt; margin: 4mm 0 1mm; page-break-after: avoid; break-after: avoid; }
table { border-collapse: collapse; width: 100%; margin: 1mm 0 3mm; }
th, td { border: 1px solid #bbb; padding: 1mm 1.6mm; text-align: left; vertical-align: top; }
th { background: #eee; }
tr { page-break-inside: avoid; break-inside: avoid; }
td.num { font-variant-numeric: tabular-nums; overflow-wrap: anywhere; }
td.src { color: #333; font-size: 9pt; }
table.inputs { table-layout: fixed; font-size: 9.5pt; }
table.inputs td { overflow-wrap: anywhere; }
table.inputs col.k { width: 23%; } table.inputs col.v { width: 17%; } table.inputs col.u { width: 8%; }
table.inputs col.m { width: 27%; } table.inputs col.s { width: 25%; }
.ok, .bad { display: inline-block; white-space: nowrap; padding: 0.4mm 2mm; border-radius: 1mm; font-weight: bold; color: #fff; -webkit-print-color-adjust: exact; print-color-adjust: exact; }
.ok { background: #1a7f37; }
.bad { background: #c62828; }
.overall { font-size: 14pt; margin: 3mm 0; padding: 3mm; border: 2px solid #333; }
.meta td:first-child { width: 32mm; font-weight: bold; }
.hash { font-family: 'DejaVu Sans Mono', monospace; font-size: 8.5pt; word-break: break-all; }
figure { margin: 2mm 0 4mm; page-break-inside: avoid; break-inside: avoid; }
figure svg { width: 100%; height: auto; display: block; border: 1px solid #ddd; }
figcaption { font-size: 9pt; color: #333; margin-top: 1mm; }
pre { white-space: pre-wrap; font-size: 8.5pt; background: #f6f6f6; border: 1px solid #ddd; padding: 2mm; }
ul { margin: 1mm 0 2mm 5mm; padding-left: 3mm; }
.na { color: #555; font-style: italic; }
";

/// The page for a scene's text; `file` names it. Returns the HTML and the overall verdict.
pub fn page(text: &str, file: &str, sweep_axes: &[String], metric: &str) -> Result<(String, bool), Failure> {
    page_with(text, file, &[], text, sweep_axes, metric)
}

/// The page for a scene read as `original` and simulated as `text` after the `--set` overrides
/// `sets` (listed on the page with both texts' SHA-256).
pub fn page_with(text: &str, file: &str, sets: &[flinch_model::overrides::Set], original: &str, sweep_axes: &[String], metric: &str) -> Result<(String, bool), Failure> {
    let sc = scene::parse(text, file).map_err(|e| Failure::bad_input(e.to_string()))?;
    let template = Template::from_text(text, file).map_err(|e| Failure::bad_input(e.to_string()))?;
    let axes = if sweep_axes.is_empty() { None } else { Some(sweep::cli::axes(sweep_axes, &[]).map_err(|e| Failure::bad_input(format!("--sweep {e}")))?) };
    if axes.is_some() {
        sweep::check_metric(metric).map_err(|e| Failure::bad_input(format!("--metric {e}")))?;
    }
    let sweep = match axes {
        Some(a) => Some(sweep::Sweep::keep_going(&template, a).map_err(|e| Failure::bad_input(format!("--sweep {e}")))?),
        None => None,
    };

    // The run, its plot.
    let run = stream::run(&sc, None, true, None).map_err(|f| Failure { message: format!("{file}: {}", f.message), ..f })?;
    let s = &run.summary;
    let history_svg = svg("run", |p| plot::draw(p, &sc, s, &run.plotted, &Trace::new(&sc), &Vec::new()));
    // The budget and the design, where the scene has a module with a stroke and a travel switch.
    let chk = check::check(&sc);
    let des = design::design(&template, None, None, None);
    let design_svg = des.as_ref().ok().map(|r| svg("design", |p| design::draw(p, &template, r)));
    let swept = sweep.map(|sw| {
        let r = sw.run(sweep::Progress::Hidden);
        let pic = svg("sweep", |p| sweep::plot::draw(p, &r, metric));
        (r, pic)
    });

    let overall = s.safe && chk.as_ref().map_or(true, |c| c.safe) && des.as_ref().map_or(true, |d| d.safe);
    let mut h = String::new();
    let w = &mut h;
    let command = crate::document::command_line();
    // The title says what was simulated, and flags a name (or description) it contradicts.
    let hl = flinch_model::headline::headline(&sc);
    let _ = write!(w, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Flinch report: {}</title><style>{CSS}{}</style></head><body>\n", esc(&hl.title().replace('\n', ": ")), crate::document::footer_css(env!("CARGO_PKG_VERSION"), &sha256_hex(text), &command));
    let _ = writeln!(w, "<h1>Flinch report: {}</h1>", esc(&sc.name));
    let _ = writeln!(w, "<p id=\"simulated\"><b>Simulated:</b> {}</p>", esc(&hl.simulated));
    for m in &s.name_mismatches {
        let _ = writeln!(w, "<p class=\"name-mismatch\"><span class=\"bad\">NAME MISMATCH</span> {}</p>", esc(m));
    }
    for m in &s.not_as_commanded {
        let _ = writeln!(w, "<p class=\"not-as-commanded\"><span class=\"bad\">NOT AS COMMANDED</span> {}</p>", esc(m));
    }
    let description = shipped::description(text);
    if !description.is_empty() && description != sc.name {
        let stale = flinch_model::headline::number_mismatches(&sc, &description);
        let _ = writeln!(w, "<p>{}</p>", crate::document::prose(&description));
        for m in stale {
            let _ = writeln!(w, "<p class=\"name-mismatch\"><span class=\"bad\">DESCRIPTION MISMATCH</span> {}</p>", esc(&m.replace("the name says", "the description says")));
        }
    }
    if !sets.is_empty() {
        let list = sets.iter().map(|s| format!("<code>{}</code>", esc(&s.shown()))).collect::<Vec<_>>().join(", ");
        let _ = writeln!(w, "<p id=\"overrides\">Overrides: {list}. The file as read has SHA-256 <span class=\"hash\">{}</span>; the simulated text (below) {}.</p>", sha256_hex(original), sha256_hex(text));
    }
    let _ = writeln!(w, "<table class=\"meta\"><tr><td>scene</td><td>{}</td></tr><tr><td>SHA-256</td><td class=\"hash\" id=\"sha256\">{}</td></tr><tr><td>tool</td><td>flinch {} (flinch-harness)</td></tr><tr><td>written</td><td id=\"written\">{}</td></tr><tr><td>command</td><td id=\"command\"><code>{}</code></td></tr><tr><td>safe means</td><td>docs/verdicts.md: the stroke left while the tool touches the target stays positive, and (check, design) the stopping-distance budget fits</td></tr></table>", esc(file), sha256_hex(text), env!("CARGO_PKG_VERSION"), crate::document::written_at(), esc(&command));

    // Verdicts.
    let _ = writeln!(w, "<h2>Verdicts</h2>");
    let _ = writeln!(w, "<p class=\"overall\" id=\"overall\">Overall: {} &mdash; {}</p>", badge(overall), if overall { "every verdict below is favourable" } else { "at least one verdict below is not favourable" });
    let _ = writeln!(w, "<table><tr><th>what</th><th>verdict</th><th>detail</th></tr>");
    let _ = writeln!(w, "<tr><td>simulation (flinch run)</td><td id=\"verdict-run\">{}</td><td>{}</td></tr>", badge(s.safe), esc(&verdict::line(s)));
    match &chk {
        Ok(c) => {
            let detail = format!("stopping distance after detection {} = {}; stroke left at detection {} (C = {}, switch at {}); budget {} (margin {})", c.stopping_law, verdict::mm(c.stopping_distance), verdict::mm(c.remaining), verdict::mm(c.stroke), verdict::mm(c.switch_travel), if c.fits { "FITS" } else { "DOES NOT FIT: escalate to a category-0 stop" }, verdict::mm_signed(c.margin));
            let _ = writeln!(w, "<tr><td>stroke budget (flinch check)</td><td id=\"verdict-check\">{}</td><td>{}{}</td></tr>", badge(c.safe), esc(&detail), c.explanations.iter().map(|e| format!("<br>why: {}", esc(e))).collect::<String>());
        }
        Err(e) => {
            let _ = writeln!(w, "<tr><td>stroke budget (flinch check)</td><td class=\"na\">not applicable</td><td class=\"na\">{}</td></tr>", esc(e));
        }
    }
    match &des {
        Ok(r) => {
            let answer = match r.speed_limit_mps {
                Some(v) => format!("the robot may go up to <b id=\"safe-speed\">{}</b> with this module (formula {}, simulated {})", esc(&verdict::mps(v)), esc(&verdict::mps(r.speed_limit_formula)), esc(&r.speed_limit_simulated.map_or("-".into(), verdict::mps))),
                None => format!("no safe speed confirmed by simulation ({}); do not rely on the formula's {} alone", esc(r.speed_search_note.as_deref().unwrap_or("")), esc(&verdict::mps(r.speed_limit_formula))),
            };
            let _ = writeln!(w, "<tr><td>safe speed (flinch design)</td><td id=\"verdict-design\">{}</td><td>at V_c = {}: {}; {}</td></tr>", badge(r.safe), esc(&verdict::mps(r.speed)), if r.safe { "safe" } else { "not safe" }, answer);
        }
        Err(e) => {
            let _ = writeln!(w, "<tr><td>safe speed (flinch design)</td><td class=\"na\">not applicable</td><td class=\"na\">{}</td></tr>", esc(e));
        }
    }
    let _ = writeln!(w, "</table>");
    // Every verdict-like field of the summary, whatever it is (fields added later appear here).
    let sj = serde_json::to_value(s).unwrap_or(Json::Null);
    if let Some(o) = sj.as_object() {
        let _ = writeln!(w, "<h3>Verdict fields of the run summary</h3><table id=\"verdict-fields\"><tr><th>field</th><th>value</th><th>unit</th></tr>");
        // A null reason beside a defined value says nothing.
        for (k, v) in o.iter().filter(|(k, v)| verdict_like(k) && crate::document::applies(k, s) && !(k.ends_with("_null_reason") && v.is_null())) {
            let _ = writeln!(w, "<tr><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>", esc(k), esc(&cell(v)), esc(&unit(k)));
        }
        let _ = writeln!(w, "</table>");
    }
    if !s.warnings.is_empty() {
        let _ = writeln!(w, "<h3>Warnings</h3><ul>{}</ul>", s.warnings.iter().map(|x| format!("<li>{}</li>", esc(x))).collect::<String>());
    }
    if let Ok(r) = &des {
        if !r.notes.is_empty() {
            let _ = writeln!(w, "<h3>Design notes</h3><ul>{}</ul>", r.notes.iter().map(|x| format!("<li>{}</li>", esc(x))).collect::<String>());
        }
    }

    if let Some(t) = crate::document::iso_ts_15066(&sc, s) {
        w.push_str(&t);
    }

    // Inputs.
    let _ = writeln!(w, "<h2>Inputs</h2><p>Every key the scene file sets, its unit and meaning from the scene contract (docs/SCENES.md), and where the value came from: the scene file's own comment.</p>");
    let _ = writeln!(w, "<table id=\"inputs\" class=\"inputs\"><colgroup><col class=\"k\"><col class=\"v\"><col class=\"u\"><col class=\"m\"><col class=\"s\"></colgroup><tr><th>key</th><th>value</th><th>unit</th><th>meaning</th><th>source (scene comment)</th></tr>");
    for i in inputs(text) {
        let _ = writeln!(w, "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"src\">{}</td></tr>", esc(&i.key), esc(&i.value), esc(&i.unit), esc(&i.meaning), if i.source.is_empty() { "<span class=\"na\">no comment in the file</span>".to_string() } else { esc(&i.source) });
    }
    let _ = writeln!(w, "</table>");

    // Figures.
    let _ = writeln!(w, "<h2>Time history</h2>");
    fig(w, "fig-run", &history_svg, "flinch run --plot: velocities, forces, travel against time");
    let _ = writeln!(w, "<h2>Design curve</h2>");
    match &design_svg {
        Some(p) => fig(w, "fig-design", p, "flinch design --plot: peak forces, the stroke margin (simulated and formula) and the working mode against speed; the safe limits marked"),
        None => {
            let _ = writeln!(w, "<p class=\"na\">not applicable: {}</p>", esc(des.as_ref().err().map_or("", String::as_str)));
        }
    }
    if let Some((r, pic)) = &swept {
        let _ = writeln!(w, "<h2>Sweep</h2>");
        let keys: Vec<String> = r.axes.iter().map(|a| a.key.clone()).collect();
        fig(w, "fig-sweep", pic, &format!("flinch sweep over {} ({} points, {} refused or failed); colour: {}", keys.join(" and "), r.points.len(), r.points.iter().filter(|p| p.status != sweep::Status::Ok).count(), sweep::plot::metric_label(metric)));
    }

    // Everything else.
    let _ = writeln!(w, "<h2>Run summary (every field)</h2><table id=\"summary\"><tr><th>field</th><th>value</th><th>unit</th></tr>");
    if let Some(o) = sj.as_object() {
        for (k, v) in o.iter().filter(|(k, _)| crate::document::applies(k, s)) {
            let _ = writeln!(w, "<tr><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>", esc(k), esc(&cell(v)), esc(&unit(k)));
        }
    }
    let _ = writeln!(w, "</table>");
    let _ = writeln!(w, "<h2>Scene file (the text hashed above)</h2><pre id=\"scene-text\">{}</pre>", esc(text));
    let _ = writeln!(w, "<p style=\"font-size:8.5pt;color:#555\">Written by flinch {} report. Lengths in mm, speeds in m/s, times in ms in the sentences; the tables keep SI units.</p>", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(w, "</body></html>");
    Ok((h, overall))
}

fn fig(w: &mut String, id: &str, svg: &Result<String, String>, caption: &str) {
    match svg {
        Ok(s) => {
            let _ = writeln!(w, "<figure id=\"{id}\">{s}<figcaption>{}</figcaption></figure>", esc(caption));
        }
        Err(e) => {
            let _ = writeln!(w, "<p class=\"na\">the figure could not be drawn: {}</p>", esc(e));
        }
    }
}

/// Runs `flinch report`.
pub fn run(a: &ReportArgs) -> Result<bool, Failure> {
    if !output::is_stdout(&a.out) && a.out.extension().and_then(|e| e.to_str()).is_none_or(|e| !matches!(e.to_ascii_lowercase().as_str(), "html" | "htm")) {
        return Err(Failure::bad_input(format!("--out {}: the report file must end in .html", a.out.display())));
    }
    let varied: Vec<&str> = a.sweep.iter().map(|v| v.split_once('=').map_or(v.as_str(), |(k, _)| k).trim()).collect();
    flinch_model::overrides::refuse_overlap(&a.set, &varied, "--sweep").map_err(Failure::bad_input)?;
    let loaded = flinch_model::overrides::load(&a.scene, &a.set).map_err(Failure::bad_input)?;
    let (file, text) = (loaded.file.clone(), loaded.text.clone());
    let (html, safe) = page_with(&text, &file, &a.set, &loaded.original, &a.sweep, &a.metric)?;
    use std::io::Write as _;
    let mut out = output::create(&a.out)?;
    out.write_all(html.as_bytes()).and_then(|_| out.flush()).map_err(|e| output::write_error(&a.out, &e))?;
    if !output::is_stdout(&a.out) {
        output::note(&format!("wrote {} ({} kB; overall {})", a.out.display(), html.len() / 1024, if safe { "SAFE" } else { "NOT SAFE" }));
    }
    Ok(safe)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sha256_of_a_known_text() {
        // FIPS 180-2 example: "abc".
        assert_eq!(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }

    #[test]
    fn inputs_keep_units_meaning_and_the_files_comments() {
        let text = shipped::get("tables5-7_bistable_stopping_table").unwrap();
        let i = inputs(text);
        let speed = i.iter().find(|x| x.key == "motion.speed").unwrap();
        assert_eq!((speed.value.as_str(), speed.unit.as_str()), ("0.25", "m/s"));
        assert!(speed.source.contains("Fig. 46-48"), "{speed:?}");
        let d = i.iter().find(|x| x.key == "motion.stopping.distance").unwrap();
        assert_eq!(d.value, "[0.005, 0.014, 0.028]");
        assert_eq!(d.source, "see motion.stopping.category");
        let c = i.iter().find(|x| x.key == "motion.stopping.category").unwrap();
        assert!(c.source.contains("ILLUSTRATIVE"), "{c:?}");
        let k = i.iter().find(|x| x.key == "decoupler.front_stop.stiffness").unwrap();
        assert!(k.source.contains("Table 6"), "{k:?}");
        let kb = i.iter().find(|x| x.key == "decoupler.spring_rate").unwrap();
        assert_eq!(kb.unit, "N/m");
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(esc("<b a=\"x\">&'"), "&lt;b a=&quot;x&quot;&gt;&amp;&#39;");
    }
}
