#!/usr/bin/env python3
"""ctest cone_in_use_script: docs/cone_in_use.py on a synthetic sweep and log.

The sweep, recovery on: runs whose cones in use were at most 1, 3.0 (a bin's
lower edge), 10.0, 12 and 25 deg off the ground, with 30, 40 (not over
40 ms), 41, 120 and 45 ms of slip after detection; a run with no slipping
sample (null fields); and a recovery-off run at 12 deg and 900 ms that the
table must leave out (and alone counts with --recovery off).
The log: LF on a 0.3 rad upslope from 0.1 s, its cone about the flat plane
until 0.25 s (17.2 deg off, 0.15 s), then about the slope, and again flat
for 0.03 s from 0.40 s (shorter than --min-s); RF in the air; LH on the flat
ground with its cone right. Standard library only.
"""

import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.normpath(os.path.join(HERE, "..", "..", "docs", "cone_in_use.py"))
LEGS = ["LF", "RF", "LH", "RH"]


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], check=True, capture_output=True, text=True).stdout


def write_case(root, k, deg, after, recovery=True):
    case = os.path.join(root, "cases", f"p{k:03d}_ode_{'on' if recovery else 'off'}_s1")
    os.makedirs(case)
    summary = {"recovery": recovery,
               "normal_in_use_error_deg": None if deg is None else {"max": deg},
               "slip_duration_after_detection_ms": None if after is None else {"median": 1, "max": after}}
    with open(os.path.join(case, "summary.json"), "w") as f:
        json.dump(summary, f)


def write_log(path):
    slope = (-math.sin(0.3), 0.0, math.cos(0.3))
    flat = (0.0, 0.0, 1.0)
    columns = ["time"] + [f"{leg}_contact" for leg in LEGS]
    columns += [f"{leg}_normal_{a}" for leg in LEGS for a in "xyz"]
    columns += [f"normal_used_{leg}_{a}" for leg in LEGS for a in "xyz"]
    with open(path, "w") as f:
        f.write(",".join(columns) + "\n")
        for tick in range(500):
            t = tick * 0.001
            row = {"time": f"{t:.3f}"}
            for leg in LEGS:
                on = (leg == "LF" and t >= 0.1) or leg == "LH"
                truth = slope if leg == "LF" and on else flat
                used = flat if leg != "LF" or t < 0.25 or 0.40 <= t < 0.43 else slope
                row[f"{leg}_contact"] = "1" if on else "0"
                for a, x, y in zip("xyz", truth, used):
                    row[f"{leg}_normal_{a}"] = f"{x:.6f}"
                    row[f"normal_used_{leg}_{a}"] = f"{y:.6f}"
            f.write(",".join(row[c] for c in columns) + "\n")


def main():
    failures = []
    with tempfile.TemporaryDirectory() as root:
        for k, (deg, after) in enumerate([(1.0, 30), (3.0, 40), (10.0, 41), (12.0, 120), (25.0, 45), (None, None)]):
            write_case(root, k, deg, after)
        write_case(root, 9, 12.0, 900, recovery=False)
        table = run(root)
        expected = ["recovery on, 6 runs", "| 0-3 | 1 | 0 | 0 | 30 |", "| 3-5 | 1 | 0 | 0 | 40 |",
                    "| 5-10 | 0 | 0 | 0 | - |", "| 10-20 | 2 | 2 | 1 | 120 |", "| 20 or more | 1 | 1 | 0 | 45 |",
                    "| no slipping sample | 1 | 0 | 0 | 0 |"]
        for line in expected:
            if line not in table:
                failures.append(f"table lacks {line!r}:\n{table}")
        off = run(root, "--recovery", "off")
        if "recovery off, 1 runs" not in off or "| 10-20 | 1 | 1 | 1 | 900 |" not in off:
            failures.append(f"recovery off:\n{off}")

        log = os.path.join(root, "log.csv")
        write_log(log)
        spans = run("--log", log)
        if "LF: largest 17.2 deg at 0.100 s; over 10 deg: 0.10-0.25 s\n" not in spans:
            failures.append(f"LF's span (the 0.03 s one left out):\n{spans}")
        if "RF: never on the ground" not in spans:
            failures.append(f"RF in the air:\n{spans}")
        if "LH: largest 0.0 deg at 0.000 s; over 10 deg: none" not in spans:
            failures.append(f"LH's cone right:\n{spans}")
        short = run("--log", log, "--min-s", "0.02")
        if "over 10 deg: 0.10-0.25 s, 0.40-0.43 s" not in short:
            failures.append(f"--min-s 0.02 keeps the short span:\n{short}")
    if failures:
        print("\n".join(failures))
        sys.exit(1)
    print("cone_in_use_script: all checks passed")


if __name__ == "__main__":
    main()
