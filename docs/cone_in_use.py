#!/usr/bin/env python3
"""How far the cone in use is from the ground, and what that costs
(design-notes.md, "The cone in use off its ground").

    build/host/hyq_sim sweep sim_host/sweeps/terrain_validation.yaml --out out/terrain_validation
    python3 docs/cone_in_use.py out/terrain_validation [--recovery on|off]
    build/host/hyq_sim run out/terrain_validation/cases/p231_ode_on_s1/scenario.yaml --seed 1 --out out/t232
    python3 docs/cone_in_use.py --log out/t232/log.csv [--deg 10] [--min-s 0.05]

With a sweep folder: its runs with the --recovery setting asked for (on;
summary.json's "recovery") binned by the largest angle between the normal of
a slipping foot's cone in use and the ground's true normal under it
(normal_in_use_error_deg, docs/metrics.md), with the runs over 40 ms and over
100 ms of slip after detection in each bin and the longest. A run with no
slipping sample has no angle and gets its own row; a run with nothing slid
after detection counts 0 ms.

With --log: each leg's spans of at least --min-s (0.05 s) on the ground
whose cone in use lies more than --deg (10 deg) off the true contact normal,
and its largest angle. Ticks over the angle closer than MERGE_GAP_S (0.05 s)
apart are one span, across a lift-off and landing between them too.
Standard library only.
"""
import argparse
import glob
import json
import math
import os
import sys

from touchdown_slips import read

BINS = [(0.0, 3.0), (3.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, math.inf)]
LEGS = ["LF", "RF", "LH", "RH"]
MERGE_GAP_S = 0.05  # [s] over-the-angle ticks closer than this are one span


def largest(summary, key):
    """A summary field's max, or None where the run has none."""
    return (summary.get(key) or {}).get("max")


def sweep_table(folder, recovery):
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "cases", "*", "summary.json"))):
        with open(path) as f:
            s = json.load(f)
        if bool(s.get("recovery")) != (recovery == "on"):
            continue
        rows.append((largest(s, "normal_in_use_error_deg"), largest(s, "slip_duration_after_detection_ms") or 0.0))
    if not rows:
        sys.exit(f"no run with recovery {recovery} under {folder}/cases")
    print(f"recovery {recovery}, {len(rows)} runs")
    print("| cone in use off the ground, run's max [deg] | runs | over 40 ms after detection | over 100 ms | longest [ms] |")
    print("|---|---|---|---|---|")
    groups = [(f"{lo:g}-{hi:g}" if hi < math.inf else f"{lo:g} or more",
               [a for n, a in rows if n is not None and lo <= n < hi]) for lo, hi in BINS]
    groups.append(("no slipping sample", [a for n, a in rows if n is None]))
    for label, after in groups:
        longest = f"{max(after):.0f}" if after else "-"
        print(f"| {label} | {len(after)} | {sum(a > 40 for a in after)} | {sum(a > 100 for a in after)} | {longest} |")


def angle_deg(a, b):
    na = math.sqrt(sum(x * x for x in a))
    nb = math.sqrt(sum(x * x for x in b))
    if na == 0.0 or nb == 0.0:
        return 0.0
    c = sum(x * y for x, y in zip(a, b)) / (na * nb)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def log_spans(path, min_deg, min_s):
    spans = {leg: [] for leg in LEGS}
    worst = {leg: None for leg in LEGS}  # (angle, time) once on the ground
    names = ["time"] + [f"{leg}_contact" for leg in LEGS]
    names += [f"{kind}{a}" for leg in LEGS for kind in (f"{leg}_normal_", f"normal_used_{leg}_") for a in "xyz"]
    cols, rows = read(path, names)
    for row in rows:
        t = row[cols["time"]]
        for leg in LEGS:
            if row[cols[leg + "_contact"]] != 1.0:
                continue
            truth = [row[cols[f"{leg}_normal_{a}"]] for a in "xyz"]
            used = [row[cols[f"normal_used_{leg}_{a}"]] for a in "xyz"]
            off = angle_deg(truth, used)
            if worst[leg] is None or off > worst[leg][0]:
                worst[leg] = (off, t)
            if off > min_deg:
                if spans[leg] and t - spans[leg][-1][1] < MERGE_GAP_S:
                    spans[leg][-1][1] = t
                else:
                    spans[leg].append([t, t])
    for leg in LEGS:
        if worst[leg] is None:
            print(f"{leg}: never on the ground")
            continue
        long_spans = [f"{a:.2f}-{b:.2f} s" for a, b in spans[leg] if b - a >= min_s]
        off, t = worst[leg]
        print(f"{leg}: largest {off:.1f} deg at {t:.3f} s; over {min_deg:g} deg: {', '.join(long_spans) or 'none'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweep", nargs="?", help="a hyq_sim sweep's output folder")
    ap.add_argument("--recovery", choices=["on", "off"], default="on", help="the sweep's runs read (default on)")
    ap.add_argument("--log", help="one run's log.csv instead")
    ap.add_argument("--deg", type=float, default=10.0, help="--log: the angle a span is over [deg]")
    ap.add_argument("--min-s", type=float, default=0.05, help="--log: the shortest span printed [s]")
    args = ap.parse_args()
    if args.log:
        log_spans(args.log, args.deg, args.min_s)
    elif args.sweep:
        sweep_table(args.sweep, args.recovery)
    else:
        ap.error("a sweep folder or --log")


if __name__ == "__main__":
    main()
