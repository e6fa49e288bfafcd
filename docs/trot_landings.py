#!/usr/bin/env python3
"""How the trot's feet come down: each leg's true foot velocity just before
touch-down and its skid after it (design-notes.md, "How a trot foot lands on
the hyq plant").

    build/host/hyq_sim run sim_host/scenarios/trot_flat.yaml --engine mujoco --seed 1 \\
        --duration 15 --quiet --out out/notes/landings/hyq
    python3 docs/trot_landings.py out/notes/landings/*

For every touch-down in a run's log.csv (the simulator's contact flag rising
after at least 80 ms in the air, past 3 s) it takes the foot's true velocity
two ticks before contact (the contact tick's own difference holds the impact)
and the foot's largest horizontal travel along x over the 20 ticks from
contact (the skid), and prints per leg their means and the largest skid.
Standard library only.
"""
import sys

from touchdown_slips import read

LEGS = ["LF", "RF", "LH", "RH"]
MIN_AIR = 0.08     # [s] a shorter lift is a bounce, not a swing
START = 3.0        # [s] the trot's start left out
SKID_TICKS = 20    # ticks after contact over which the skid is taken


def landings(path):
    """{leg: [(vx, vz, skid), ...]} of one run's log.csv, in m/s and m."""
    names = ["time"] + [f"{leg}_{k}" for leg in LEGS for k in ("contact", "foot_pos_x", "foot_pos_z")]
    cols, rows = read(path, names)
    time = [r[cols["time"]] for r in rows]
    dt = time[1] - time[0]
    out = {leg: [] for leg in LEGS}
    for leg in LEGS:
        x = [r[cols[leg + "_foot_pos_x"]] for r in rows]
        z = [r[cols[leg + "_foot_pos_z"]] for r in rows]
        contact = [r[cols[leg + "_contact"]] == 1.0 for r in rows]
        lift = None
        for k in range(3, len(rows) - SKID_TICKS):
            if contact[k - 1] and not contact[k]:
                lift = time[k]
            if not contact[k] or contact[k - 1] or lift is None:
                continue
            if time[k] - lift < MIN_AIR or time[k] < START:
                continue
            vx = (x[k - 2] - x[k - 3]) / dt
            vz = (z[k - 2] - z[k - 3]) / dt
            skid = max(abs(x[k + j] - x[k]) for j in range(SKID_TICKS))
            out[leg].append((vx, vz, skid))
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for run in sys.argv[1:]:
        parts = []
        for leg, items in landings(run + "/log.csv").items():
            if not items:
                continue
            n = len(items)
            vx = sum(i[0] for i in items) / n
            vz = sum(i[1] for i in items) / n
            skid = 1000.0 * sum(i[2] for i in items) / n
            worst = 1000.0 * max(i[2] for i in items)
            parts.append(f"{leg} vx {vx:+.2f} vz {vz:+.2f} m/s skid {skid:.1f} mm (max {worst:.1f})")
        print(run + ": " + "; ".join(parts))


if __name__ == "__main__":
    main()
