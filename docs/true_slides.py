#!/usr/bin/env python3
"""The slides a run offered to the friction estimate, by the simulator's
own record: design-notes.md, "What a soft contact hides from the
estimator" (the x0.3 ramp) and "Why a landing front foot gets no estimate".

    build/host/hyq_sim run <scenario.yaml> --recovery on --seed 6 --out out/notes/soft_ramp_6
    python3 docs/true_slides.py out/notes/soft_ramp_6 [more run folders]

A slide is a stretch of at least --min-ticks ticks (5) in which a foot in
contact carries more than --min-load (50 N) along its true normal, its true
force ratio |F_t| / F_n is within 5 % of the ground's mu (at the cone), and
its contact point moves faster than 0.02 m/s. For each slide the script
prints its start [s], leg, mu, length [ticks], the normal load's range
[N], the peak slip speed [m/s], whether the controller flagged that leg
within 5 ticks before to 20 ticks after it, and the leg's mu_hat 20 ticks
after its end (0: no estimate). The columns come from the run's log.csv:
<leg>_force_*, <leg>_normal_*, <leg>_slip_vel_*, <leg>_mu, slip_mask and
mu_hat_<leg>.
"""
import argparse
import math
import os

from touchdown_slips import read

LEGS = ["LF", "RF", "LH", "RH"]
MIN_SPEED = 0.02      # [m/s]
AT_CONE = 0.95        # [-] force ratio over mu
FLAG_BEFORE = 5       # [ticks]
FLAG_AFTER = 20       # [ticks]


def slides(cols, rows, leg, min_ticks, min_load):
    bit = 1 << LEGS.index(leg)
    f = [cols[f"{leg}_force_{a}"] for a in "xyz"]
    n = [cols[f"{leg}_normal_{a}"] for a in "xyz"]
    v = [cols[f"{leg}_slip_vel_{a}"] for a in "xyz"]
    mu_col, hat_col, mask_col = cols[f"{leg}_mu"], cols[f"mu_hat_{leg}"], cols["slip_mask"]

    def state(row):
        force = [row[c] for c in f]
        normal = [row[c] for c in n]
        fn = sum(a * b for a, b in zip(force, normal))
        ft = math.sqrt(max(0.0, sum(a * a for a in force) - fn * fn))
        speed = math.sqrt(sum(row[c] ** 2 for c in v))
        sliding = fn > min_load and ft >= AT_CONE * row[mu_col] * fn and speed > MIN_SPEED
        return sliding, fn, speed

    out = []
    states = [state(row) for row in rows]
    i = 0
    while i < len(rows):
        if not states[i][0]:
            i += 1
            continue
        j = i
        while j < len(rows) and states[j][0]:
            j += 1
        if j - i >= min_ticks:
            loads = [s[1] for s in states[i:j]]
            window = rows[max(0, i - FLAG_BEFORE):min(len(rows), j + FLAG_AFTER)]
            flagged = any(int(r[mask_col]) & bit for r in window)
            after = rows[min(len(rows) - 1, j + FLAG_AFTER)][hat_col]
            out.append((rows[i][cols["time"]], leg, rows[i][mu_col], j - i, min(loads), max(loads),
                        max(s[2] for s in states[i:j]), flagged, after))
        i = j
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("runs", nargs="+", help="run folders (each with a log.csv)")
    p.add_argument("--min-ticks", type=int, default=5)
    p.add_argument("--min-load", type=float, default=50.0, help="[N]")
    a = p.parse_args()
    for run in a.runs:
        cols, rows = read(os.path.join(run, "log.csv"))
        found = sorted(s for leg in LEGS for s in slides(cols, rows, leg, a.min_ticks, a.min_load))
        print(f"{run}: {len(found)} slides")
        for t, leg, mu, ticks, lo, hi, peak, flagged, hat in found:
            print(f"  {t:8.3f} s  {leg}  mu {mu:.2f}  {ticks:3d} ticks  {lo:4.0f}-{hi:4.0f} N"
                  f"  peak {peak:.3f} m/s  {'flagged' if flagged else 'not flagged'}"
                  f"  mu_hat after {hat:.3f}")


if __name__ == "__main__":
    main()
