#!/usr/bin/env python3
"""The GRF estimate's error after a trot landing: design-notes.md, "A trot
slide's samples share one error".

    for s in 3 7 11 32; do build/host/hyq_sim run sim_host/scenarios/trot_ice_patches.yaml \\
        --seed $s --quiet --out out/notes/trot_force/s$s; done
    python3 docs/trot_force_error.py out/notes/trot_force/s*

For every foot in contact (the simulator's truth) it groups the ticks by the
time since that foot's touch-down, in 5 ms bins, and by whether the contact
point slides (faster than 0.05 m/s), and prints the mean and the spread of
the controller's GRF estimate (grf_est, W) minus the true contact force, per
axis. A row's telemetry answers that tick's sensor frame, whose torques
drove the step before: it is compared with the previous row's force (that
step's). The telemetry's estimate is the tick's own, with the joint
accelerations of a 10-tick fit (not the estimator's samples, which pair
each force with the acceleration centred on it).
"""
import csv
import math
import statistics
import sys

LEGS = ["LF", "RF", "LH", "RH"]
SLIDE_SPEED = 0.05  # [m/s]
BIN_MS = 5
LAST_BIN_MS = 100   # later ticks share one bin


def main(dirs):
    bins = {}
    for d in dirs:
        with open(d + "/log.csv") as f:
            reader = csv.reader(f)
            head = next(reader)
            ix = {k: i for i, k in enumerate(head)}
            since = [0] * 4
            previous = None
            for row in reader:
                for k, leg in enumerate(LEGS):
                    in_contact = float(row[ix[leg + "_contact"]]) > 0.5
                    since[k] = since[k] + 1 if in_contact else 0
                    if not in_contact or since[k] < 2:
                        continue
                    b = min(since[k] // BIN_MS * BIN_MS, LAST_BIN_MS)
                    err = [float(row[ix["grf_est_%s_%s" % (leg, a)]]) - float(previous[ix["%s_force_%s" % (leg, a)]])
                           for a in "xyz"]
                    speed = math.sqrt(sum(float(row[ix["%s_slip_vel_%s" % (leg, a)]]) ** 2 for a in "xyz"))
                    bins.setdefault((b, speed > SLIDE_SPEED), []).append(err)
                previous = row
    print("| since touch-down [ms] | sliding | ticks | error x [N] | error y [N] | error z [N] |")
    print("|---|---|---|---|---|---|")
    for (b, sliding), errs in sorted(bins.items()):
        if len(errs) < 30:
            continue
        label = "%d-%d" % (b, b + BIN_MS - 1) if b < LAST_BIN_MS else ">= %d" % LAST_BIN_MS
        cells = ["%+.1f +- %.1f" % (statistics.mean(e[i] for e in errs), statistics.pstdev(e[i] for e in errs))
                 for i in range(3)]
        print("| %s | %s | %d | %s |" % (label, "yes" if sliding else "no", len(errs), " | ".join(cells)))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
