#!/usr/bin/env python3
"""ctest long_slides_script: docs/long_slides.py on a synthetic sweep.

Five cases in the sweep's sweep.csv, each with its events.csv and (already
in the work folder, so nothing is run again) log.csv. The LF foot slides from 0.100 s
to 0.170 s; its flag rises at 0.110 s, so 60 ms after detection:
- a crawl whose LF knee stands at its stop through the slide: "at a stop kfe";
- a trot (two feet in stance on some ticks): "trot";
- a crawl whose LF is put in stance at 0.080 s and touches at 0.095 s:
  "stance in the air";
- a crawl whose worst slide is 30 ms, under the 40 ms the script asks for:
  not listed;
- a run with recovery off: not listed (the script reads recovery on).
Checks each case's line and the counts. Standard library only.
"""

import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.normpath(os.path.join(HERE, "..", "..", "docs", "long_slides.py"))
COLUMNS = ["time", "stance_mask", "LF_contact", "q_LF_haa", "q_LF_hfe", "q_LF_kfe"]


def write_case(root, case, worst_ms, trot=False, knee_at_stop=False, stance_at=0.0, contact_at=0.0, recovery=True):
    case_dir = os.path.join(root, "cases", case)
    os.makedirs(case_dir)
    sweep_csv = os.path.join(root, "sweep.csv")
    with open(sweep_csv, "a") as f:
        if f.tell() == 0:
            f.write("id,recovery,terrain.generate.seed,after_detection_max_ms\n")
        f.write(f"{case},{'on' if recovery else 'off'},7,{worst_ms}\n")
    end = 0.110 + worst_ms / 1000.0
    with open(os.path.join(case_dir, "events.csv"), "w") as f:
        f.write("time,tick,event,leg,detail\n")
        f.write("0.100,100,slip_start,LF,speed 0.06 m/s, mu 0.3\n")
        f.write("0.110,110,slip_flag_on,LF,\n")
        f.write(f"{end:.3f},{round(end * 1000)},slip_end,LF,\n")
        f.write(f"{end + 0.005:.3f},{round(end * 1000) + 5},slip_flag_off,LF,\n")
    log_dir = os.path.join(root, "long_slides", case)
    os.makedirs(log_dir)
    with open(os.path.join(log_dir, "log.csv"), "w") as f:
        f.write(",".join(COLUMNS) + "\n")
        for tick in range(300):
            t = tick / 1000.0
            stance = 15 if t >= stance_at else 14
            if trot and 200 <= tick < 220:
                stance = 9
            contact = 1 if t >= contact_at else 0
            knee = -0.345 if knee_at_stop else -1.4
            f.write(f"{t:.3f},{stance},{contact},-0.2,0.7,{knee}\n")
    with open(os.path.join(root, "long_slides", case, "events.csv"), "w") as f, \
            open(os.path.join(case_dir, "events.csv")) as src:
        f.write(src.read())


def main():
    failures = []
    with tempfile.TemporaryDirectory() as root:
        write_case(root, "p000", 60, knee_at_stop=True)
        write_case(root, "p001", 60, trot=True)
        write_case(root, "p002", 60, stance_at=0.080, contact_at=0.095)
        write_case(root, "p003", 30)
        write_case(root, "p004", 60, knee_at_stop=True, recovery=False)
        r = subprocess.run([sys.executable, SCRIPT, root, "--sim", "/nonexistent"], capture_output=True, text=True)
        out = r.stdout
        expect = [
            "p000 terrain 7: 60 ms, LF at 0.100 s, at a stop kfe",
            "p001 terrain 7: 60 ms, LF at 0.100 s, trot",
            "p002 terrain 7: 60 ms, LF at 0.100 s, stance in the air",
            "at a stop: 1 runs, 0 over 100 ms, longest 60 ms",
            "trot: 1 runs, 0 over 100 ms, longest 60 ms",
            "stance in the air: 1 runs, 0 over 100 ms, longest 60 ms",
        ]
        if r.returncode != 0:
            failures.append(f"exit {r.returncode}: {r.stderr}")
        for e in expect:
            if e not in out:
                failures.append(f"missing '{e}'")
        if "p003" in out:
            failures.append("p003 (30 ms) listed")
        if "p004" in out:
            failures.append("p004 (recovery off) listed")
    for f in failures:
        print("FAIL:", f)
    if failures:
        print(out)
        return 1
    print("long_slides_script: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
