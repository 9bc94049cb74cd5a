//! Every command block of README.md, run as written against the built `flinch`, from a scratch
//! directory that links the repository's `scenes/` and `docs/`. Where the README shows what a
//! command prints (a ```text block after a ```sh block, with only prose between), the standard
//! output of the block's last command that runs must be exactly that. Blocks are ```sh; `cargo run --release --bin flinch --` is
//! the built binary. Not run, each for its stated reason: `cargo xtask test` (it is what runs this
//! test), and any line ending in a `# long: why` comment (none today).

use std::path::{Path, PathBuf};
use std::process::Command;

struct Block {
    commands: Vec<String>,
    expected: Option<String>,
}

fn blocks(readme: &str) -> Vec<Block> {
    let mut out: Vec<Block> = Vec::new();
    let mut lines = readme.lines();
    let mut last_sh: Option<usize> = None;
    while let Some(l) = lines.next() {
        let Some(lang) = l.strip_prefix("```") else { continue };
        let body: Vec<&str> = lines.by_ref().take_while(|x| !x.starts_with("```")).collect();
        match lang.trim() {
            "sh" => {
                let mut commands = Vec::new();
                for c in body.iter().map(|x| x.trim()).filter(|x| !x.is_empty() && !x.starts_with('#')) {
                    commands.push(c.to_string());
                }
                out.push(Block { commands, expected: None });
                last_sh = Some(out.len() - 1);
            }
            "text" | "" => {
                if let Some(i) = last_sh.take() {
                    out[i].expected = Some(body.join("\n") + "\n");
                }
            }
            _ => last_sh = None,
        }
    }
    out
}

fn scratch() -> PathBuf {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap();
    let d = std::env::temp_dir().join(format!("flinch-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("bin")).unwrap();
    for link in ["scenes", "docs"] {
        std::os::unix::fs::symlink(repo.join(link), d.join(link)).unwrap();
    }
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_flinch"), d.join("bin").join("flinch")).unwrap();
    d
}

#[test]
fn every_readme_command_runs_and_prints_what_the_readme_shows() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md")).unwrap();
    let bs = blocks(&readme);
    assert!(bs.len() >= 3, "the README's command blocks were not found");
    let dir = scratch();
    let path = format!("{}:{}", dir.join("bin").display(), std::env::var("PATH").unwrap_or_default());
    let (mut ran, mut compared, mut skipped) = (0, 0, Vec::new());
    for b in &bs {
        let mut last: Option<(String, String)> = None;
        for c in &b.commands {
            if c.starts_with("cargo xtask test") {
                skipped.push(format!("{c}: it is the command that runs this test"));
                continue;
            }
            if let Some((_, why)) = c.split_once("# long:") {
                skipped.push(format!("{c}: long ({})", why.trim()));
                continue;
            }
            let cmd = c.replace("cargo run --release --bin flinch --", "flinch");
            assert!(cmd.starts_with("flinch "), "README command not understood: {c}");
            let o = Command::new("sh").arg("-c").arg(&cmd).current_dir(&dir).env("PATH", &path).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "README command failed ({:?}): {c}\n{err}", o.status.code());
            assert!(!err.contains("panicked"), "{c}: {err}");
            ran += 1;
            last = Some((c.clone(), String::from_utf8_lossy(&o.stdout).into_owned()));
        }
        // The output shown belongs to the block's last command that runs.
        if let (Some(want), Some((c, got))) = (&b.expected, &last) {
            assert_eq!(got, want, "README output of `{c}` differs");
            compared += 1;
        }
    }
    eprintln!("README: {ran} commands ran, {compared} outputs compared; not run: {skipped:?}");
    assert!(ran >= 8 && compared >= 2, "{ran} ran, {compared} compared");
    let _ = std::fs::remove_dir_all(&dir);
}
