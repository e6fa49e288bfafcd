#!/usr/bin/env python3
"""ctest plots_script: docs/plots.py on a tiny synthetic run directory.

Writes log.csv (the hyq_sim column names, 400 rows at 1 kHz, one synthetic LF
slip with its controller flag), summary.json and events.csv into a temporary
directory, runs docs/plots.py on it and checks that the four PNGs exist and are
not empty. Also: a run without any slip flag gets figs 5-6 only, --compare
works, and a directory without log.csv exits with status 2.
Standard library only (plots.py itself finds numpy/matplotlib).
"""

import csv
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.normpath(os.path.join(HERE, "..", "..", "docs", "plots.py"))
LEGS = ("LF", "RF", "LH", "RH")
XYZ = ("x", "y", "z")
FIGS = ("fig5_mu.png", "fig6_odometry.png", "fig7_normal.png", "fig8_slip_flags.png")


def columns():
    c = ["time", "tick", "base_pos_x", "base_pos_y", "base_pos_z", "base_qw", "base_qx", "base_qy", "base_qz",
         "base_vel_x", "base_vel_y", "base_vel_z", "base_omega_x", "base_omega_y", "base_omega_z"]
    for leg in LEGS:
        c += [f"{leg}_contact"] + [f"{leg}_force_{a}" for a in XYZ] + [f"{leg}_mu"]
        c += [f"{leg}_normal_{a}" for a in XYZ] + [f"{leg}_slip_vel_{a}" for a in XYZ]
        c += [f"{leg}_foot_pos_{a}" for a in XYZ]
    c += [f"disturbance_{a}" for a in XYZ]
    joints = [f"{leg}_{j}" for leg in LEGS for j in ("haa", "hfe", "kfe")]
    c += [f"q_{j}" for j in joints] + [f"qd_{j}" for j in joints] + [f"tau_{j}" for j in joints]
    c += ["imu_qw", "imu_qx", "imu_qy", "imu_qz"] + [f"imu_gyro_{a}" for a in XYZ] + [f"imu_acc_{a}" for a in XYZ]
    c += [f"tau_cmd_{j}" for j in joints]
    c += ["flags", "stance_mask", "slip_mask", "swing_leg", "gait_phase"]
    c += [f"base_pos_est_{a}" for a in XYZ] + [f"base_vel_est_{a}" for a in XYZ]
    for pre in ("foot_vel_base", "grf_est", "grf_des"):
        c += [f"{pre}_{leg}_{a}" for leg in LEGS for a in XYZ]
    c += [f"mu_used_{leg}" for leg in LEGS]
    c += [f"normal_used_{leg}_{a}" for leg in LEGS for a in XYZ]
    c += [f"mu_hat_{leg}" for leg in LEGS]
    c += [f"normal_hat_{leg}_{a}" for leg in LEGS for a in XYZ]
    return c


def write_run(d, with_slip=True, rows=400, recovery=True):
    cols = columns()
    slip = range(150, 230) if with_slip else range(0)      # ground-truth slip of LF
    flag = range(160, 240) if with_slip else range(0)      # controller flag of LF
    with open(os.path.join(d, "log.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        mu_hat, n_used = 0.0, [0.0, 0.0, 1.0]
        for k in range(rows):
            t = 0.001 * (k + 1)
            r = dict.fromkeys(cols, 0.0)
            r.update(time=f"{t:.3f}", tick=k, base_qw=1.0, imu_qw=1.0, base_pos_z=0.6, base_pos_est_z=0.6)
            r["base_pos_x"] = 0.1 * t
            r["base_pos_est_x"] = 0.1 * t + (0.002 * (k - 150) / 80 if k >= 150 else 0.0)
            r["stance_mask"] = 15
            r["swing_leg"] = 4
            r["slip_mask"] = 1 if k in flag else 0
            r["flags"] = 8 if 200 <= k < 210 and with_slip else 0
            for i, leg in enumerate(LEGS):
                r[f"{leg}_contact"] = 1
                r[f"{leg}_mu"] = 0.25 if leg == "LF" else 0.8
                r[f"{leg}_normal_z"] = 1.0
                r[f"{leg}_force_z"] = 200.0
                r[f"tau_{leg}_kfe"] = 60.0 + 2.0 * math.sin(0.02 * k)
                for a, v in zip(XYZ, (-0.1, 0.0, 0.01)):
                    r[f"foot_vel_base_{leg}_{a}"] = v
                r[f"mu_used_{leg}"] = 0.6
                r[f"normal_used_{leg}_z"] = 1.0
            if k in slip:
                r["LF_slip_vel_x"] = 0.3
                r["LF_force_x"] = 0.25 * 200.0
                r["foot_vel_base_LF_x"] = 0.2
            if k in flag:
                mu_hat = 0.27 - 0.0002 * (k - 160)
                n_used = [n_used[0] + 0.1 * (0.05 - n_used[0]), 0.0, 1.0]
            r["mu_hat_LF"] = mu_hat
            r["mu_used_LF"] = 0.6 if mu_hat == 0 else max(mu_hat, 0.3)
            if mu_hat > 0:
                r["normal_hat_LF_x"], r["normal_hat_LF_z"] = 0.05, 0.9987
            r["normal_used_LF_x"], r["normal_used_LF_z"] = n_used[0], n_used[2]
            w.writerow([r[c] for c in cols])
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump({"scenario": "synthetic", "recovery": recovery, "fell": False, "slip_events": int(with_slip)}, f)
    with open(os.path.join(d, "events.csv"), "w") as f:
        f.write("time,tick,event,leg,detail\n0.001,0,touchdown,LF,\n")
        if with_slip:
            f.write("0.151,150,slip_start,LF,\"speed 0.3 m/s, mu 0.25\"\n0.161,160,slip_flag_on,LF,\n"
                    "0.230,229,slip_end,LF,\n0.241,240,slip_flag_off,LF,\n")


def run(args):
    p = subprocess.run([sys.executable, SCRIPT] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=300)
    sys.stdout.write(p.stdout)
    sys.stderr.write(p.stderr)
    return p


def check_pngs(d, names):
    for n in names:
        path = os.path.join(d, n)
        assert os.path.isfile(path), f"missing {path}"
        size = os.path.getsize(path)
        assert size > 1000, f"{path} is only {size} bytes"
        with open(path, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"


def main():
    with tempfile.TemporaryDirectory(prefix="plots_test_") as tmp:
        slip_dir = os.path.join(tmp, "slip")
        calm_dir = os.path.join(tmp, "calm")
        empty_dir = os.path.join(tmp, "empty")
        for d in (slip_dir, calm_dir, empty_dir):
            os.mkdir(d)
        write_run(slip_dir, with_slip=True)
        write_run(calm_dir, with_slip=False, recovery=False)

        p = run([slip_dir, "--compare", calm_dir])
        assert p.returncode == 0, f"plots.py failed with status {p.returncode}"
        check_pngs(slip_dir, FIGS)
        for n in FIGS:
            assert os.path.join(slip_dir, n) in p.stdout, f"{n} not in the printed list"
        assert "LF" in p.stdout, "the chosen slip event (LF) is not reported"

        p = run([slip_dir, "--leg", "LF", "--t", "0.2"])
        assert p.returncode == 0, f"plots.py --leg/--t failed with status {p.returncode}"
        check_pngs(slip_dir, FIGS)

        p = run([calm_dir])
        assert p.returncode == 0, f"plots.py on a run without slip failed with status {p.returncode}"
        check_pngs(calm_dir, FIGS[:2])
        for n in FIGS[2:]:
            assert not os.path.exists(os.path.join(calm_dir, n)), f"{n} written for a run without slip"
        assert "skipped" in p.stdout, "no note about the skipped figures"

        p = run([empty_dir])
        assert p.returncode == 2, f"missing log.csv: expected status 2, got {p.returncode}"
        assert len(p.stderr.strip().splitlines()) == 1, "expected a one-line message"
    print("plots_script: OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
