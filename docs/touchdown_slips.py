#!/usr/bin/env python3
"""How well a lightly loaded slip's friction could be read from the GRF
estimate: design-notes.md, "Why a landing front foot gets no estimate".

    for s in 1 2 3 4 5 6 7 8; do build/host/hyq_sim run sim_host/scenarios/ice_patches.yaml \\
        --seed $s --quiet --out out/notes/touchdown/s$s; done
    python3 docs/touchdown_slips.py out/notes/touchdown/s*

For every slip in the runs' log.csv (ground truth: the contact point faster
than 0.02 m/s, the foot in contact, for at least 10 ticks) on ground with
mu <= 0.5 and with a true normal load under 40 N on average, it compares
three ratios of the controller's GRF estimate (grf_est, W; the ground is
flat) with the true mu:

  - sum |F_t| / sum F_n        (the per-tick tangential force's norm)
  - |sum F_t| / sum F_n        (the tangential forces averaged first)
  - sum -F_t . v / sum F_n     (the force along the true slip direction v)

and prints, per front and hind legs, the spread of the errors and the GRF
estimate's error (estimate - truth) during those ticks.
"""
import csv
import math
import os
import statistics
import sys

LEGS = ["LF", "RF", "LH", "RH"]
MIN_SPEED = 0.02   # [m/s]
MIN_TICKS = 10
MAX_LOAD = 40.0    # [N]
MAX_MU = 0.5


def read(path, names=None):
    """A run's log.csv: its column indices by name, and its rows as floats
    (an empty field is NaN); with names, those columns only (a long log
    reads several times faster). docs/true_slides.py, docs/long_slides.py,
    docs/trot_landings.py and docs/cone_in_use.py read logs with it too."""
    with open(path) as f:
        r = csv.reader(f)
        head = next(r)
        keep = [head.index(n) for n in names] if names else range(len(head))
        cols = {head[i]: k for k, i in enumerate(keep)}
        return cols, [[float(row[i]) if row[i] else math.nan for i in keep] for row in r]


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    errors = {"front": {"norm": [], "vector": [], "along": []}, "hind": {"norm": [], "vector": [], "along": []}}
    force_err = {"front": [[], [], []], "hind": [[], [], []]}
    loads = {"front": [], "hind": []}
    for run in sys.argv[1:]:
        cols, rows = read(os.path.join(run, "log.csv"))
        for li, leg in enumerate(LEGS):
            side = "front" if li < 2 else "hind"
            c = lambda k: cols[f"{leg}_{k}"]
            e = lambda k: cols[f"grf_est_{leg}_{k}"]
            group = []
            for t, row in enumerate(rows + [None]):
                sliding = row is not None and row[c("contact")] > 0.5 and \
                    (row[c("slip_vel_x")] ** 2 + row[c("slip_vel_y")] ** 2) ** 0.5 > MIN_SPEED
                if sliding:
                    group.append(row)
                    continue
                if len(group) >= MIN_TICKS and group[0][c("mu")] <= MAX_MU and \
                        statistics.mean(r[c("force_z")] for r in group) < MAX_LOAD:
                    mu = group[0][c("mu")]
                    fn = sum(r[e("z")] for r in group)
                    norm = sum((r[e("x")] ** 2 + r[e("y")] ** 2) ** 0.5 for r in group)
                    sx, sy = sum(r[e("x")] for r in group), sum(r[e("y")] for r in group)
                    along = 0.0
                    for r in group:
                        vx, vy = r[c("slip_vel_x")], r[c("slip_vel_y")]
                        v = (vx * vx + vy * vy) ** 0.5
                        along -= (r[e("x")] * vx + r[e("y")] * vy) / v
                    if fn > 0:
                        errors[side]["norm"].append(100 * (norm / fn - mu) / mu)
                        errors[side]["vector"].append(100 * ((sx * sx + sy * sy) ** 0.5 / fn - mu) / mu)
                        errors[side]["along"].append(100 * (along / fn - mu) / mu)
                        loads[side].append(statistics.mean(r[c("force_z")] for r in group))
                        for k, axis in enumerate("xyz"):
                            force_err[side][k] += [r[e(axis)] - r[c("force_" + axis)] for r in group]
                group = []
    names = {"norm": "sum |F_t| / sum F_n", "vector": "|sum F_t| / sum F_n", "along": "sum -F_t.v / sum F_n"}
    for side in ("front", "hind"):
        n = len(errors[side]["norm"])
        if n == 0:
            print(f"{side}: no light slip")
            continue
        print(f"{side} feet: {n} light slips, true load median {statistics.median(loads[side]):.0f} N; "
              "GRF estimate - truth, sd x/y/z: " +
              " / ".join(f"{statistics.pstdev(force_err[side][k]):.1f}" for k in range(3)) + " N")
        for key, label in names.items():
            xs = errors[side][key]
            print(f"  {label:22s} error median {statistics.median(xs):+5.0f} %, p10 {pct(xs, 0.1):+5.0f}, "
                  f"p90 {pct(xs, 0.9):+5.0f}; within 10 %: {sum(abs(x) <= 10 for x in xs)}/{n}")


if __name__ == "__main__":
    main()
