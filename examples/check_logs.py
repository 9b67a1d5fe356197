#!/usr/bin/env python3
"""Run `decophantom check --json` over every dive in a folder of dive logs and tabulate.

Usage: python3 examples/check_logs.py [FOLDER] [CRITERIA]
       (defaults: tests/data/divelogs and algorithms/criteria/default.toml)
Needs the decophantom binary on PATH or in target/release (cargo build --release).
Each dive of each Subsurface (.xml, .ssrf) or UDDF (.uddf) file is checked; closed-circuit
dives and other refused inputs (exit code 2) are listed with the error. JSON schema:
docs/json.md (decophantom.check/1).
"""
import json
import pathlib
import shutil
import subprocess
import sys

folder = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "tests/data/divelogs")
criteria = sys.argv[2] if len(sys.argv) > 2 else "algorithms/criteria/default.toml"
exe = shutil.which("decophantom") or "target/release/decophantom"


def check(log, dive):
    cmd = [exe, "check", "--schedule", str(log), "--dive", str(dive),
           "--criteria", criteria, "--json", "--quiet"]
    return subprocess.run(cmd, capture_output=True, text=True)


rows = []
for log in sorted(p for p in folder.iterdir() if p.suffix.lower() in (".xml", ".ssrf", ".uddf")):
    dive = 1
    while True:
        r = check(log, dive)
        if r.returncode in (0, 1):
            out = json.loads(r.stdout)
            scores = {s["kind"]: s for s in out["run"]["scores"]}
            worst = max(out["run"]["scores"], key=lambda s: s["value"] / s["limit"])
            rows.append((log.name, dive, out["candidate"]["schedule"]["max_depth_m"],
                         out["candidate"]["schedule"]["runtime_min"],
                         scores.get("peak-radius", {}).get("value", float("nan")),
                         worst["kind"], worst["value"] / worst["limit"],
                         "pass" if out["all_pass"] else "FAIL"))
        elif "does not exist" in r.stderr:
            break  # past the last dive of this log
        else:
            rows.append((log.name, dive, None, None, None, r.stderr.strip().splitlines()[-1], None, "refused"))
        dive += 1

print(f"{'file':<26} {'dive':>4} {'max m':>6} {'min':>6} {'peak R µm':>9}  {'worst criterion':<28} {'v/limit':>7}  result")
refusals = []
for f, d, depth, runtime, radius, worst, ratio, result in rows:
    if depth is None:
        refusals.append(worst)
        print(f"{f:<26} {d:>4} {'':>6} {'':>6} {'':>9}  {'(refused: note ' + str(len(refusals)) + ')':<28} {'':>7}  {result}")
    else:
        print(f"{f:<26} {d:>4} {depth:>6.1f} {runtime:>6.1f} {radius:>9.1f}  {worst:<28} {ratio:>7.3f}  {result}")
# the refusals whole, after the table (a message names the file, line and field)
for i, message in enumerate(refusals, 1):
    print(f"note {i}: {message}")
