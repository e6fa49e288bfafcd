#!/usr/bin/env python3
"""The end of `make run`: two runs of one scenario side by side, beside the paper.

    python3 docs/run_report.py ON_DIR OFF_DIR

ON_DIR and OFF_DIR are hyq_sim run directories (summary.json, and the
figures docs/plots.py wrote there) of the same scenario with slip recovery on
and off. Prints a table of what each run did (fell, distance, slip events,
detection latency, slip duration after detection, friction and normal
errors, odometry error per 50 cm, false detections) with the paper's figure
for the ice patches beside it, then the paths of the figures and logs, and
last those of the runs' 3D replays (replay.html, from hyq_sim's --replay).
Metric definitions: docs/metrics.md. Standard library only.
Exit status 2 when a directory has no readable summary.json.
"""

import glob
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import results  # noqa: E402  (GOALS, reached, odo_per_50cm_cm, fmt)

# Focchi et al., Sec. 5, ice patches (mu 0.25, 0.2, 0.3, 0.15): one run each.
PAPER_ICE_PATCHES = {
    "fell": ("crossed all patches", "fell after a few steps"),
    "mu": "< 13 % (with recovery)",
    "odometry": ("< 1 cm", "18 cm"),
}


def load(run_dir):
    path = os.path.join(run_dir, "summary.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        print(f"run_report: {path}: {e}", file=sys.stderr)
        return None


def ms(block, key):
    v = block.get(key)
    return "-" if v is None else results.fmt(v, 0)


def rows(on, off, scenario):
    goal = results.GOALS.get(scenario)
    paper = PAPER_ICE_PATCHES if scenario == "ice_patches" else None

    def both(get):
        return [get(on), get(off)]

    def fell(r):
        return f"yes, at {r['fall_time_s']:.1f} s" if r["fell"] else "no"

    out = [
        ("fell", *both(fell), f"on: {paper['fell'][0]}; off: {paper['fell'][1]}" if paper else ""),
        ("distance [m]", *both(lambda r: f"{r['distance_m']:.2f}"), ""),
    ]
    if goal:
        out.append((goal[1], *both(lambda r: "yes" if results.reached(scenario, r) else "no"), ""))
    out += [
        ("slip events (true, in stance)", *both(lambda r: str(r["slip_events"])), ""),
        ("missed slips", *both(lambda r: str(r["missed_slips"])), ""),
        ("false detections", *both(lambda r: str(r["false_detections"])), ""),
        ("detection latency, median / max [ms]",
         *both(lambda r: f"{ms(r['detection_latency_ms'], 'median')} / {ms(r['detection_latency_ms'], 'max')}"), ""),
        ("slip after detection, median / max [ms]",
         *both(lambda r: f"{ms(r['slip_duration_after_detection_ms'], 'median')} / "
                         f"{ms(r['slip_duration_after_detection_ms'], 'max')}"), ""),
        ("mu error, worst event [%]", *both(lambda r: results.fmt(r["mu_estimate_error_pct"]["max"], 1)),
         paper["mu"] if paper else ""),
        ("normal error, worst event [deg]", *both(lambda r: results.fmt(r["normal_error_deg"]["max"], 1)), ""),
        ("odometry error per 50 cm [cm]", *both(lambda r: results.fmt(results.odo_per_50cm_cm(r), 2)),
         f"on: {paper['odometry'][0]}; off: {paper['odometry'][1]}" if paper else ""),
        ("freezes", *both(lambda r: str(r["freeze_events"])), ""),
        ("simulator speed [x real time]", *both(lambda r: f"{r['real_time_factor']:.0f}"), ""),
    ]
    return out


def table(header, body):
    widths = [max(len(str(row[i])) for row in [header] + body) for i in range(len(header))]
    line = lambda row: "  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip()
    return [line(header), line(["-" * w for w in widths])] + [line(r) for r in body]


def files(run_dir):
    found = sorted(glob.glob(os.path.join(run_dir, "fig*.png")))
    found += [os.path.join(run_dir, n) for n in ("log.csv", "events.csv", "summary.json")
              if os.path.exists(os.path.join(run_dir, n))]
    return found


def replay(run_dir):
    path = os.path.join(run_dir, "replay.html")
    return path if os.path.exists(path) else None


def main(argv=None):
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    on_dir, off_dir = args
    on, off = load(on_dir), load(off_dir)
    if on is None or off is None:
        return 2
    scenario = on["scenario"]
    print()
    print(f"{scenario}, seed {on['seed']}, {on['sim_time_s']:.0f} s simulated on {on['engine']}: "
          f"slip recovery on vs off")
    print()
    paper_col = "paper (Focchi et al.)" if scenario == "ice_patches" else ""
    for line in table(["", "recovery on", "recovery off", paper_col], [list(r) for r in rows(on, off, scenario)]):
        print(line)
    print()
    print("Metric definitions: docs/metrics.md; over many seeds: docs/results.md.")
    for label, d in (("recovery on", on_dir), ("recovery off", off_dir)):
        print(f"{label}:")
        for p in files(d):
            print(f"  {p}")
    replays = [(label, replay(d)) for label, d in (("recovery on", on_dir), ("recovery off", off_dir))]
    if any(p for _, p in replays):
        print("3D replays (open in a browser; docs/replay.md):")
        for label, p in replays:
            if p:
                print(f"  {label + ':':14s}{p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
