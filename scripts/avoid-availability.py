#!/usr/bin/env python3
"""The availability table of docs/avoidance.md (issue 29): each scene run four ways with the same
binary, side by side: SSM alone (as shipped), SSM + PFL with the bi-stable module of Tables 5-7
(scenes/body_hand.toml, its axis along start -> goal), SSM + PFL with a rigid tool
(scenes/body_hand_rigid.toml, same axis), and the thesis's law (--thesis). max_time_s is raised to
40 s for all four, so a slow tool is not cut off. Regions: hand and lower arm.

Usage: scripts/avoid-availability.py [path/to/flinch]   (default: target/debug/flinch)
Writes the scenes it runs to a temporary directory; prints one Markdown row per scene."""
import json, math, os, re, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "debug", "flinch")
SCENES = ["avoid_thesis_reach", "avoid_hand_side_wide", "avoid_operator_hand", "avoid_head_on_wide",
          "avoid_moving_hand_wide", "avoid_forearm_across", "avoid_fast_hand", "avoid_hand_behind",
          "avoid_tray_beside_goal"]


def xy(key, text):
    return [float(v) for v in re.search(key + r"\s*=\s*\[([^\]]*)\]", text).group(1).split(",")]


def run(path, extra=()):
    p = subprocess.run([BIN, "avoid", path, "--json", *extra], capture_output=True, text=True)
    try:
        return json.loads(p.stdout)
    except ValueError:
        return {"status": "error", "reason": p.stderr.strip()[:80]}


def cell(m):
    s = m.get("status", "?") + (f" ({m['reason']})" if m.get("reason") else "")
    if m.get("time_to_goal_s") is not None:
        s += f", {m['time_to_goal_s']:.2f} s"
    if m.get("path_length_m") is not None:
        s += f", {m['path_length_m']:.2f} m"
    if m.get("min_signed_distance_m") is not None:
        s += f", min {m['min_signed_distance_m'] * 1000:.0f} mm"
    if m.get("steps_in_pfl"):
        s += f", {m['steps_in_pfl']} steps in PFL"
    return s


with tempfile.TemporaryDirectory() as tmp:
    for name in SCENES:
        text = open(os.path.join(ROOT, "scenes", name + ".toml")).read()
        text = re.sub(r"max_time_s\s*=\s*[0-9.]+", "max_time_s = 40.0", text)
        a, b = xy("start_m", text), xy("goal_m", text)
        n = math.hypot(b[0] - a[0], b[1] - a[1])
        axis = [(b[0] - a[0]) / n, (b[1] - a[1]) / n]
        base = os.path.join(tmp, name + ".toml")
        open(base, "w").write(text)
        row = [cell(run(base))]
        for module in ["body_hand.toml", "body_hand_rigid.toml"]:
            path = os.path.join(tmp, name + "_" + module)
            pfl = (f'\n[avoid.pfl]\nmodule = "{os.path.join(ROOT, "scenes", module)}"\n'
                   f'body_regions = ["hand", "lower_arm"]\naxis = [{axis[0]:.6f}, {axis[1]:.6f}]\n')
            open(path, "w").write(text.rstrip("\n") + "\n" + pfl)
            row.append(cell(run(path)))
        row.append(cell(run(base, ["--thesis"])))
        print(f"| `{name}` | " + " | ".join(row) + " |", flush=True)
