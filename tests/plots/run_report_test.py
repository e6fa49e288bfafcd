#!/usr/bin/env python3
"""ctest run_report_script: docs/run_report.py on two synthetic run directories.

Writes the summary.json of an ice_patches run with recovery on (crossed, no
fall) and one with recovery off (fell at 41.5 s) and checks the table's
cells: each run's figures in its column, the paper's beside them, the goal
row, the listed files and replays; and that a directory without summary.json exits 2.
Standard library only.
"""

import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.normpath(os.path.join(HERE, "..", "..", "docs", "run_report.py"))


def summary(recovery, fell):
    return {
        "scenario": "ice_patches", "seed": 3, "recovery": recovery, "engine": "ode",
        "sim_time_s": 90.0 if not fell else 41.5, "fell": fell, "fall_time_s": 41.5 if fell else None,
        "distance_m": 4.31 if recovery else 2.02, "real_time_factor": 51.2,
        "slip_events": 47 if recovery else 158, "missed_slips": 12 if recovery else 30,
        "false_detections": 0 if recovery else 2,
        "detection_latency_ms": {"median": 9, "max": 41},
        "slip_duration_after_detection_ms": {"median": 5, "max": 12} if recovery else {"median": 130, "max": None},
        "mu_estimate_error_pct": {"max": 4.26 if recovery else None, "per_leg": [None] * 4, "per_patch": []},
        "normal_error_deg": {"max": 0.4},
        "odometry_error_m": {"final": 0.002, "max": 0.0093 if recovery else 0.31},
        "distance_walked_m": 4.65 if recovery else 2.1,
        "freeze_events": 0 if recovery else 1,
    }


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def row(out, label):
    for line in out.splitlines():
        if line.startswith(label):
            return line[len(label):].split()
    raise AssertionError(f"no row '{label}' in:\n{out}")


def main():
    failures = []

    def check(cond, what):
        if not cond:
            failures.append(what)

    with tempfile.TemporaryDirectory() as tmp:
        on, off = os.path.join(tmp, "on"), os.path.join(tmp, "off")
        for d, rec, fell in ((on, True, False), (off, False, True)):
            os.makedirs(d)
            with open(os.path.join(d, "summary.json"), "w") as f:
                json.dump(summary(rec, fell), f)
        open(os.path.join(on, "fig5_mu.png"), "wb").close()
        r = run(on, off)
        check("3D replays" not in r.stdout, "replays listed without replay.html")
        for d in (on, off):
            open(os.path.join(d, "replay.html"), "w").close()
        r = run(on, off)
        check(r.returncode == 0, f"exit {r.returncode}: {r.stderr}")
        out = r.stdout
        check("ice_patches, seed 3" in out, "title")
        check(row(out, "fell")[:4] == ["no", "yes,", "at", "41.5"], f"fell: {row(out, 'fell')}")
        check("fell after a few steps" in out, "paper's fell cell")
        check(row(out, "distance [m]") == ["4.31", "2.02"], f"distance: {row(out, 'distance [m]')}")
        # The hind feet past the last patch: 4.31 - 0.37 > 3.4, 2.02 - 0.37 is not.
        check(row(out, "past the last patch") == ["yes", "no"], "goal row")
        check(row(out, "slip events (true, in stance)") == ["47", "158"], "slip events")
        check(row(out, "false detections") == ["0", "2"], "false detections")
        check(row(out, "slip after detection, median / max [ms]") == ["5", "/", "12", "130", "/", "-"],
              f"after detection: {row(out, 'slip after detection, median / max [ms]')}")
        check(row(out, "mu error, worst event [%]")[:2] == ["4.3", "-"], "mu error")
        check("< 13 %" in out, "paper's mu cell")
        # 0.0093 m over 4.65 m walked: 0.10 cm per 50 cm; 0.31 m over 2.1 m: 7.38.
        check(row(out, "odometry error per 50 cm [cm]")[:2] == ["0.10", "7.38"],
              f"odometry: {row(out, 'odometry error per 50 cm [cm]')}")
        check(row(out, "freezes") == ["0", "1"], "freezes")
        check(os.path.join(on, "fig5_mu.png") in out and os.path.join(off, "summary.json") in out, "file list")
        # The replays last, one line each.
        tail = out.rstrip().splitlines()[-3:]
        check(tail[0].startswith("3D replays") and tail[1].endswith(os.path.join(on, "replay.html"))
              and tail[2].endswith(os.path.join(off, "replay.html")), f"replays: {tail}")
        empty = os.path.join(tmp, "empty")
        os.makedirs(empty)
        r = run(on, empty)
        check(r.returncode == 2, f"missing summary: exit {r.returncode}")
        check(run(on).returncode == 2, "one argument: exit 2")

    for f in failures:
        print("FAIL:", f)
    print("run_report_script:", "ok" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
