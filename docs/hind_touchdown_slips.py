#!/usr/bin/env python3
"""Hind-foot touch-down slips on patches a front foot has estimated:
design-notes.md, "The friction probe".

    # one copy of sim_host/scenarios/ice_patches.yaml per configuration:
    # plain.yaml as it is; map.yaml with controller.friction_map: true;
    # both.yaml with controller.friction_map and controller.friction_probe true
    for cfg in plain map both; do for s in 1 2 3 4; do
      build/host/hyq_sim run $cfg.yaml --seed $s --quiet --out out/notes/hind/${cfg}_s$s
    done; done
    python3 docs/hind_touchdown_slips.py out/notes/hind/plain_s* -- out/notes/hind/map_s* \
        -- out/notes/hind/both_s*

For each group of runs (separated by --), it counts the true slips of a hind
foot (events.csv's slip starts and ends, merged and at least 5 ms long as
summary.json counts them) that start within 0.15 s of that foot's
touch-down on ground of mu < 0.5, split by whether a front foot had a
friction estimate (log.csv's mu_hat > 0) on ground of the same mu before.
"""
import csv
import sys

TOUCHDOWN_WINDOW = 0.15  # [s]
ICE = 0.5                # [-] ground below this mu counts as a patch
# A slip as summary.json counts one (docs/metrics.md): events.csv's slip
# starts and ends merged across gaps shorter than MERGE_GAP, and kept if
# they last at least MIN_DURATION (a landing's 1-2 ms impact is not one).
MERGE_GAP = 0.02         # [s]
MIN_DURATION = 0.005     # [s]


def analyse(run):
    rows = list(csv.DictReader(open(run + "/log.csv")))
    times = [float(r["time"]) for r in rows]
    estimated = {}  # patch mu -> earliest time a front foot had an estimate on it
    for r in rows:
        for leg in ("LF", "RF"):
            mu = round(float(r[leg + "_mu"]), 3)
            if mu < ICE and float(r["mu_hat_" + leg]) > 0 and r[leg + "_contact"] == "1":
                estimated.setdefault(mu, float(r["time"]))
    touchdowns = {"LH": [], "RH": []}
    spans = {"LH": [], "RH": []}  # [start, end] of each slip, merged
    for e in list(csv.reader(open(run + "/events.csv")))[1:]:
        time, kind, leg = float(e[0]), e[2], e[3]
        if leg not in touchdowns:
            continue
        if kind == "touchdown":
            touchdowns[leg].append(time)
        elif kind == "slip_start":
            if spans[leg] and time - spans[leg][-1][1] < MERGE_GAP:
                spans[leg][-1][1] = None  # reopened
            else:
                spans[leg].append([time, None])
        elif kind == "slip_end" and spans[leg]:
            spans[leg][-1][1] = time
    end = times[-1] if times else 0.0
    slips = sorted((start, leg) for leg in spans for start, stop in spans[leg]
                   if (end if stop is None else stop) - start >= MIN_DURATION)
    known = unknown = 0
    for time, leg in slips:
        if not any(0 <= time - t <= TOUCHDOWN_WINDOW for t in touchdowns[leg]):
            continue
        i = min(range(len(times)), key=lambda k: abs(times[k] - time))
        mu = round(float(rows[i][leg + "_mu"]), 3)
        if mu >= ICE:
            continue
        if mu in estimated and estimated[mu] < time:
            known += 1
        else:
            unknown += 1
    return known, unknown


def main():
    groups, group = [], []
    for arg in sys.argv[1:]:
        if arg == "--":
            groups.append(group)
            group = []
        else:
            group.append(arg)
    groups.append(group)
    for runs in groups:
        known = unknown = 0
        for run in runs:
            k, u = analyse(run)
            known += k
            unknown += u
        print(f"{' '.join(runs)}: hind touch-down slips on patches a front foot had estimated {known}, "
              f"on others {unknown}")


if __name__ == "__main__":
    main()
