#!/usr/bin/env python3
"""ctest trot_landings_script: docs/trot_landings.py on a synthetic run.

A 5 s log.csv at 1 kHz. LF lifts off at 4.000 s and touches down at
4.200 s; before contact it moves at +0.3 m/s along x and -0.5 m/s along z,
and after contact it skids 2 mm forward over 4 ticks and stands. A bounce
(RF in the air for 20 ms) and a landing before 3 s (LH) are no swings; RH
stands throughout. Checks the line's figures. Standard library only.
"""

import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.normpath(os.path.join(HERE, "..", "..", "docs", "trot_landings.py"))
LEGS = ["LF", "RF", "LH", "RH"]


def lf_state(tick):
    """LF's (contact, x, z) at a tick."""
    if tick < 4000:
        return 1, 0.0, 0.02
    if tick < 4200:
        # in the air: at the end moving at (+0.3, -0.5) m/s
        return 0, 0.3 * (tick - 4200) / 1000.0 + 0.2, 0.02 - 0.5 * (tick - 4200) / 1000.0
    skid = min(tick - 4200, 4) * 0.0005  # 2 mm over 4 ticks
    return 1, 0.2 + skid, 0.02


def contact_of(leg, tick):
    if leg == "RF":
        return 0 if 4100 <= tick < 4120 else 1
    if leg == "LH":
        return 0 if 2000 <= tick < 2200 else 1
    return 1


def write_log(path):
    with open(path, "w") as f:
        columns = ["time"] + [f"{leg}_{k}" for leg in LEGS for k in ("contact", "foot_pos_x", "foot_pos_z")]
        f.write(",".join(columns) + "\n")
        for tick in range(5000):
            row = [f"{(tick + 1) / 1000.0:.3f}"]
            for leg in LEGS:
                if leg == "LF":
                    c, x, z = lf_state(tick)
                else:
                    c, x, z = contact_of(leg, tick), 0.0, 0.02
                row += [str(c), f"{x:.6f}", f"{z:.6f}"]
            f.write(",".join(row) + "\n")


def main():
    with tempfile.TemporaryDirectory() as root:
        write_log(os.path.join(root, "log.csv"))
        out = subprocess.run([sys.executable, SCRIPT, root], capture_output=True, text=True, check=True).stdout
    print(out, end="")
    expected = "LF vx +0.30 vz -0.50 m/s skid 2.0 mm (max 2.0)"
    if expected not in out:
        sys.exit(f"trot_landings_script: expected '{expected}'")
    for leg in ("RF", "LH", "RH"):
        if f"{leg} vx" in out:
            sys.exit(f"trot_landings_script: {leg} has no swing landing and must not be listed")
    print("trot_landings_script: all checks passed")


if __name__ == "__main__":
    main()
