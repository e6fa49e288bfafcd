#!/usr/bin/env python3
"""Figures of a hyq_sim run, after Figures 5-8 of Focchi et al.,
"Slip Detection and Recovery for Quadruped Robots".

    python3 docs/plots.py RUN_DIR [--compare OTHER_RUN_DIR] [--leg LF|RF|LH|RH] [--t SECONDS]
    make plots RUN=out/<name>

Reads RUN_DIR/log.csv (only the columns it needs), RUN_DIR/summary.json and
RUN_DIR/events.csv, and writes into RUN_DIR:

  fig5_mu.png          mu_hat / mu_used per leg vs ground-truth mu; % error of mu_hat
  fig6_odometry.png    leg-odometry error (x, y, z) and covered distance;
                       with --compare: OTHER run upper panel, RUN lower panel
  fig7_normal.png      one slip event: n used, n_hat, ground-truth n (x, y, z);
                       friction-cone violation and knee torque of a diagonal stance leg
  fig8_slip_flags.png  one slip event: |u_i| of the four feet, slip flags vs ground truth
  fig_friction_map.png the controller's friction map, cell by cell, over the true friction
                       (only when the run kept a map: RUN_DIR/friction_map.json)

The slip event of figs 7-8 is the longest run of a controller slip flag
(slip_mask bit, bit i = leg i in LF, RF, LH, RH order); --leg restricts the
choice to one leg, --t picks the flag run nearest to that time (or, if there is
none, centres the window on it). Runs without any slip flag get figs 5-6 only.

Exit status: 0 on success, 2 if RUN_DIR/log.csv (or OTHER_RUN_DIR/log.csv) is missing.
"""

import argparse
import csv
import json
import os
import sys
from array import array

try:
    import numpy as np
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:  # e.g. a pyenv python3 first on PATH: use Debian's, which has them
    if os.path.exists("/usr/bin/python3") and os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") \
            and not os.environ.get("HYQ_PLOTS_REEXEC"):
        os.environ["HYQ_PLOTS_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    sys.stderr.write("plots.py: needs numpy and matplotlib (Debian: python3-numpy python3-matplotlib)\n")
    sys.exit(1)

LEGS = ("LF", "RF", "LH", "RH")
DIAGONAL = {"LF": "RH", "RF": "LH", "LH": "RF", "RH": "LF"}
LEG_COLORS = {"LF": "#1f77b4", "RF": "#d62728", "LH": "#2ca02c", "RH": "#ff7f0e"}
XYZ = ("x", "y", "z")
TRUE_SLIP_SPEED = 0.05   # m/s, docs/metrics.md
DETECT_TH = 0.055        # m/s, detector threshold on |s_i - median| (SlipParams::threshold)
PAPER_MU_ERR = 13.0      # %, the paper's bound on the mu estimate error
FREEZE_BIT = 1 << 3

plt.rcParams.update({
    "font.size": 11,
    "axes.titlesize": 12,
    "axes.labelsize": 11,
    "legend.fontsize": 9,
    "xtick.labelsize": 10,
    "ytick.labelsize": 10,
    "lines.linewidth": 1.4,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "legend.framealpha": 0.85,
    "savefig.dpi": 130,
})


# ----------------------------------------------------------------------------- input

def needed_columns():
    cols = ["time", "stance_mask", "slip_mask", "flags", "probe_leg", "probe_partner", "probes_found",
            "base_pos_x", "base_pos_y", "base_pos_z",
            "base_pos_est_x", "base_pos_est_y", "base_pos_est_z",
            "imu_qw", "imu_qx", "imu_qy", "imu_qz"]
    for leg in LEGS:
        cols += [f"{leg}_contact", f"{leg}_mu", f"mu_hat_{leg}", f"mu_used_{leg}",
                 f"tau_{leg}_kfe"]
        for c in XYZ:
            cols += [f"{leg}_force_{c}", f"{leg}_normal_{c}", f"{leg}_slip_vel_{c}",
                     f"normal_used_{leg}_{c}", f"normal_hat_{leg}_{c}",
                     f"foot_vel_base_{leg}_{c}"]
    return cols


def _to_float(s):
    try:
        return float(s)
    except ValueError:
        return float("nan")


def read_log(path, wanted):
    """Columns `wanted` of log.csv as a dict name -> float64 array (NaN if absent)."""
    with open(path, newline="") as f:
        reader = csv.reader(f)
        try:
            header = next(reader)
        except StopIteration:
            header = []
        pos = {name.strip(): i for i, name in enumerate(header)}
        present = [c for c in wanted if c in pos]
        idx = [pos[c] for c in present]
        ncol = len(header)
        buf = array("d")
        nrows = 0
        for row in reader:
            if len(row) != ncol:      # truncated last line of a crashed run, blank line
                continue
            try:
                buf.extend(float(row[i]) for i in idx)
            except ValueError:
                buf.extend(_to_float(row[i]) for i in idx)
            nrows += 1
    data = np.frombuffer(buf, dtype=np.float64).reshape(nrows, len(idx)) if idx else np.empty((nrows, 0))
    out = {c: data[:, k] for k, c in enumerate(present)}
    missing = [c for c in wanted if c not in pos]
    for c in missing:
        out[c] = np.full(nrows, np.nan)
    return out, missing, nrows


def read_summary(run_dir):
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def read_events(run_dir):
    ev = []
    try:
        with open(os.path.join(run_dir, "events.csv"), newline="") as f:
            for row in csv.DictReader(f):
                try:
                    ev.append((float(row.get("time", "nan")), row.get("event", ""), row.get("leg", ""),
                               row.get("detail", "")))
                except (TypeError, ValueError):
                    pass
    except OSError:
        pass
    return ev


class Run:
    def __init__(self, run_dir):
        self.dir = run_dir
        self.log_path = os.path.join(run_dir, "log.csv")
        self.d, self.missing, self.n = read_log(self.log_path, needed_columns())
        self.summary = read_summary(run_dir)
        self.events = read_events(run_dir)
        self.t = self.d["time"]

    @property
    def name(self):
        s = self.summary.get("scenario") or os.path.basename(os.path.normpath(self.dir))
        return str(s)

    @property
    def recovery(self):
        r = self.summary.get("recovery")
        if r is None:
            return "recovery ?"
        return "recovery on" if r else "recovery off"

    @property
    def label(self):
        return f"{self.name}, {self.recovery}"

    def fall_time(self):
        if self.summary.get("fell") and self.summary.get("fall_time_s") is not None:
            return float(self.summary["fall_time_s"])
        for t, e, _, _ in self.events:
            if e == "fall":
                return t
        return None

    def bits(self, name, i):
        v = self.d[name]
        out = np.zeros(self.n, dtype=bool)
        ok = np.isfinite(v)
        out[ok] = (v[ok].astype(np.int64) >> i) & 1 == 1
        return out

    def contact(self, leg):
        return self.d[f"{leg}_contact"] > 0.5

    def vec(self, fmt, leg):
        return np.stack([self.d[fmt.format(leg=leg, c=c)] for c in XYZ], axis=1)

    def true_slip(self, leg):
        sv = np.linalg.norm(self.vec("{leg}_slip_vel_{c}", leg), axis=1)
        return self.contact(leg) & (sv > TRUE_SLIP_SPEED)


# ----------------------------------------------------------------------------- helpers

def runs_of(mask):
    """[(start_index, end_index_inclusive)] of the True runs of a boolean array."""
    if mask.size == 0:
        return []
    m = np.concatenate(([False], mask, [False])).astype(np.int8)
    d = np.diff(m)
    starts = np.nonzero(d == 1)[0]
    ends = np.nonzero(d == -1)[0] - 1
    return list(zip(starts.tolist(), ends.tolist()))


def shade_runs(ax, t, mask, **kw):
    first = True
    for s, e in runs_of(mask):
        t0 = t[s]
        t1 = t[e] + (t[1] - t[0] if t.size > 1 else 0.001)
        if first:
            ax.axvspan(t0, t1, **kw)
            first = False
            kw = dict(kw)
            kw.pop("label", None)
        else:
            ax.axvspan(t0, t1, **kw)


def masked(v, mask):
    out = np.array(v, dtype=float, copy=True)
    out[~mask] = np.nan
    return out


def save(fig, path, written):
    fig.savefig(path)
    plt.close(fig)
    written.append(path)


def pick_slip(run, leg=None, t_req=None):
    """(leg, i_start, i_end, why) of the chosen controller slip flag run, or None.

    --t: the flag run nearest to t_req. Otherwise the longest flag run among the
    "real" ones: the foot in contact on at least half of its ticks, a ground-truth
    slip of the same leg that it detects (one slipping tick within [rise - 50 ms,
    end]: the slip starts by the flag's last tick and ends at most 50 ms before
    its rise, docs/metrics.md), and over at least 1 s before a fall; if no run qualifies,
    the longest flag run of all.
    """
    cands = []
    for i, lg in enumerate(LEGS):
        if leg and lg != leg:
            continue
        flag_runs = runs_of(run.bits("slip_mask", i))
        if not flag_runs:
            continue
        con = run.contact(lg)
        gt = run.true_slip(lg)
        for s, e in flag_runs:
            lo = int(np.searchsorted(run.t, run.t[s] - 0.050))
            hi = int(np.searchsorted(run.t, run.t[e], side="right"))
            real = bool(gt[lo:hi].any()) and con[s:e + 1].mean() >= 0.5
            cands.append((lg, s, e, real))
    if not cands:
        return None
    if t_req is not None:
        def dist(c):
            t0, t1 = run.t[c[1]], run.t[c[2]]
            return 0.0 if t0 <= t_req <= t1 else min(abs(t0 - t_req), abs(t1 - t_req))
        c = min(cands, key=dist)
        return c[0], c[1], c[2], f"nearest to t = {t_req:g} s"
    fall = run.fall_time()
    good = [c for c in cands if c[3] and (fall is None or run.t[c[2]] < fall - 1.0)]
    longest = lambda cs: max(cs, key=lambda c: (c[2] - c[1], -c[1]))
    if good:
        c = longest(good)
        return c[0], c[1], c[2], "longest flag run matching a true slip, foot in contact, before any fall"
    c = longest(cands)
    return c[0], c[1], c[2], "longest flag run"


def true_slip_events(run, leg, merge_gap=0.020, min_dur=0.005):
    """Ground-truth slip events of a leg as in docs/metrics.md: runs of contact & speed > 0.05 m/s,
    merged across gaps <= 20 ms, at least 5 ms long. [(i_start, i_end)]."""
    evs = []
    for a, b in runs_of(run.true_slip(leg)):
        if evs and run.t[a] - run.t[evs[-1][1]] <= merge_gap + 1e-9:
            evs[-1] = (evs[-1][0], b)
        else:
            evs.append((a, b))
    return [(a, b) for a, b in evs if run.t[b] - run.t[a] + 1e-9 >= min_dur - 0.001]


def true_slip_note(run, ev):
    """'; true slip -X..+Y ms' for the ground-truth events matching the flag run (metrics window)."""
    leg, s, e = ev
    t0, t1 = run.t[s] - 0.050, run.t[e]
    m = [(a, b) for a, b in true_slip_events(run, leg) if run.t[b] >= t0 and run.t[a] <= t1]
    if not m:
        return f"; no ground-truth slip of {leg} matches it"
    ts = 1000.0 * (run.t[m[0][0]] - run.t[s])
    te = 1000.0 * (run.t[m[-1][1]] - run.t[s]) + 1.0
    return f"; true slip from {ts:+.0f} to {te:+.0f} ms of detection"


def flag_text(run, ev):
    leg, s, e = ev
    if not run.bits("slip_mask", LEGS.index(leg))[s]:
        return f"no slip flag, window centred on t = {run.t[s]:.3f} s"
    dur = 1000.0 * (run.t[e] - run.t[s]) + 1.0
    return f"flag up for {dur:.0f} ms from t = {run.t[s]:.3f} s"


def window(run, t_center, before, after):
    return (run.t >= t_center - before) & (run.t <= t_center + after)


# ----------------------------------------------------------------------------- fig 5

def mu_error_pct(run, leg):
    """% error of mu_hat while an estimate exists and the foot is in contact (NaN elsewhere)."""
    mu_hat = run.d[f"mu_hat_{leg}"]
    mu_gt = run.d[f"{leg}_mu"]
    ok = np.isfinite(mu_hat) & (mu_hat > 0) & run.contact(leg) & (mu_gt > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        err = 100.0 * np.abs(mu_hat - mu_gt) / mu_gt
    return masked(err, ok), ok


def probe_finds(run):
    """(tick index, leg index) of each friction probe that found a foot's
    friction (a break-away): the tick its found counter rose, and of the
    two feet its pair was on the tick before, the one whose estimate
    changes on the next tick (the probed foot, or its partner if that one
    broke away)."""
    found = run.d["probes_found"]
    out = []
    if run.n < 3 or not np.any(np.isfinite(found)):
        return out
    for k in np.nonzero(np.diff(found) > 0)[0] + 1:
        if k + 1 >= run.n:
            continue
        feet = [run.d[name][k - 1] for name in ("probe_leg", "probe_partner")]
        feet = [int(f) for f in feet if np.isfinite(f) and 0 <= f < len(LEGS)]
        changed = [f for f in feet if run.d[f"mu_hat_{LEGS[f]}"][k + 1] != run.d[f"mu_hat_{LEGS[f]}"][k - 1]]
        if changed or feet:
            out.append((int(k), (changed or feet)[0]))
    return out


def fig5_mu(run, out, written):
    from matplotlib.lines import Line2D
    t = run.t
    probes = probe_finds(run)
    shown = lambda k: min(k + 1, run.n - 1)  # the tick the probe's answer shows in mu_hat
    fig, axes = plt.subplots(5, 1, figsize=(12, 10), sharex=True,
                             gridspec_kw={"height_ratios": [1, 1, 1, 1, 1.7]})
    fig.subplots_adjust(left=0.075, right=0.80, top=0.93, bottom=0.06, hspace=0.12)
    fall = run.fall_time()
    # y range: ground truth, mu used, and the bulk of the estimates before any fall
    mu_top = 0.1
    pre = np.ones(run.n, dtype=bool) if fall is None else (t < fall)
    for leg in LEGS:
        for name in (f"{leg}_mu", f"mu_used_{leg}"):
            v = run.d[name][pre]
            if np.any(np.isfinite(v)):
                mu_top = max(mu_top, float(np.nanmax(v)))
        v = run.d[f"mu_hat_{leg}"][pre]
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            mu_top = max(mu_top, float(np.percentile(v, 99.5)))
    mu_top = min(mu_top, 1.5)
    for k, leg in enumerate(LEGS):
        ax = axes[k]
        col = LEG_COLORS[leg]
        con = run.contact(leg)
        mu_hat = run.d[f"mu_hat_{leg}"]
        has_hat = np.isfinite(mu_hat) & (mu_hat > 0)
        # flagged intervals as a light band: where the estimate is being formed
        shade_runs(ax, t, run.bits("slip_mask", k), color=col, alpha=0.12, lw=0)
        ax.plot(t, run.d[f"mu_used_{leg}"], color="0.45", lw=1.0, label="$\\mu$ used by QP")
        ax.plot(t, masked(run.d[f"{leg}_mu"], con), color="k", lw=1.5, ls="--", dashes=(4, 2),
                label="$\\mu_{gt}$ (foot in contact)")
        ax.plot(t, masked(mu_hat, has_hat), color=col, lw=1.8, label="$\\hat\\mu$ estimate")
        found = [shown(kk) for kk, l in probes if l == k]
        if found:
            ax.plot(t[found], mu_hat[found], "*", ms=11, mfc=col, mec="k", mew=0.7, ls="none", zorder=5)
        ax.set_ylim(0, mu_top * 1.1)
        ax.set_ylabel(f"{leg}\n$\\mu$ [-]")
        if fall is not None:
            ax.axvline(fall, color="k", lw=1.0, ls=":")
    axes[0].legend(handles=[Line2D([], [], color="0.3", lw=1.8, label="$\\hat\\mu$ estimate (leg colour)"),
                            Line2D([], [], color="k", lw=1.5, ls="--", dashes=(4, 2),
                                   label="$\\mu_{gt}$ ground truth\n(while foot in contact)"),
                            Line2D([], [], color="0.45", lw=1.0, label="$\\mu$ used by QP"),
                            matplotlib.patches.Patch(color="0.5", alpha=0.25, label="slip flag up")]
                   + ([Line2D([], [], marker="*", ls="none", mfc="0.6", mec="k", ms=11,
                              label=f"friction probe's answer ({len(probes)})")] if probes else []),
                   loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    if fall is not None:
        axes[0].text(fall, 1.02, "fall", transform=axes[0].get_xaxis_transform(), ha="center",
                     va="bottom", fontsize=9)

    axe = axes[4]
    ymax_data = 0.0
    for k, leg in enumerate(LEGS):
        col = LEG_COLORS[leg]
        err, ok = mu_error_pct(run, leg)
        axe.plot(t, err, color=col, lw=1.1, label=leg)
        if np.any(np.isfinite(err)):
            ymax_data = max(ymax_data, float(np.nanpercentile(err[np.isfinite(err)], 99)))
        # the summary's sample (docs/metrics.md): last flagged tick of each flag run
        smp = [e for _, e in runs_of(run.bits("slip_mask", k)) if ok[e]]
        if smp:
            axe.plot(t[smp], err[smp], "o", ms=5.5, mfc=col, mec="k", mew=0.7, ls="none")
        found = [shown(kk) for kk, l in probes if l == k and ok[shown(kk)]]
        if found:
            axe.plot(t[found], err[found], "*", ms=11, mfc=col, mec="k", mew=0.7, ls="none", zorder=5)
    axe.axhline(PAPER_MU_ERR, color="k", lw=1.0, ls="--")
    if fall is not None:
        axe.axvline(fall, color="k", lw=1.0, ls=":")
    top = min(max(2.5 * PAPER_MU_ERR, ymax_data * 1.1), 150.0)
    axe.set_ylim(0, top)
    axe.set_ylabel("$|\\hat\\mu-\\mu_{gt}|/\\mu_{gt}$ [%]")
    axe.set_xlabel("time [s]")
    h, l = axe.get_legend_handles_labels()
    h += [Line2D([], [], marker="o", ls="none", mfc="0.6", mec="k", ms=5.5),
          Line2D([], [], color="k", lw=1.0, ls="--")]
    l += ["end of a slip flag\n(summary.json sample)", f"paper: < {PAPER_MU_ERR:g} %"]
    if probes:
        h.append(Line2D([], [], marker="*", ls="none", mfc="0.6", mec="k", ms=11))
        l.append("friction probe's answer")
    axe.legend(h, l, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axe.text(0.005, 0.96, "error while $\\hat\\mu>0$ and the foot is in contact"
             + (f" (axis clipped at {top:.0f} %)" if ymax_data * 1.1 > top else ""),
             transform=axe.transAxes, ha="left", va="top", fontsize=9,
             bbox=dict(fc="white", ec="none", alpha=0.8))
    if t.size:
        axe.set_xlim(t[0], t[-1])
    fig.suptitle(f"Fig. 5 - friction coefficient estimate per leg ({run.label})", fontsize=13)
    save(fig, os.path.join(out, "fig5_mu.png"), written)


# ----------------------------------------------------------------------------- fig 6

def odometry(run):
    if run.n == 0:
        return np.zeros((0, 3)), np.zeros(0)
    est = np.stack([run.d[f"base_pos_est_{c}"] for c in XYZ], axis=1)
    tru = np.stack([run.d[f"base_pos_{c}"] for c in XYZ], axis=1)
    err = (est - est[0]) - (tru - tru[0])
    dist = tru[:, 0] - tru[0, 0]
    return err, dist


ODO_COLORS = ("#1f77b4", "#2ca02c", "#d62728")


def odo_panel(ax, run, ylim):
    err, dist = odometry(run)
    t = run.t
    for k, c in enumerate(XYZ):
        ax.plot(t, 100.0 * err[:, k], color=ODO_COLORS[k], lw=1.6, label=f"error {c}")
    ax.set_ylabel("odometry error [cm]")
    ax.axhline(0, color="0.5", lw=0.6)
    ax.set_ylim(*ylim)
    ax2 = ax.twinx()
    ax2.grid(False)
    ax2.plot(t, dist, color="k", lw=2.0, label="covered distance x (right axis)")
    ax2.set_ylabel("covered distance x [m]")
    fall = run.fall_time()
    before = np.ones(run.n, dtype=bool) if fall is None else (t < fall)
    if fall is not None:
        ax.axvline(fall, color="k", lw=1.0, ls=":")
        ax.text(fall, 0.03, "fall ", transform=ax.get_xaxis_transform(), fontsize=9, va="bottom", ha="right")
    txt = ""
    if np.any(before) and np.any(np.isfinite(err[before, 0])):
        eb = err[before]
        i = int(np.nanargmax(np.abs(eb[:, 0])))
        txt = (f"{'before the fall' if fall is not None else 'whole run'}: "
               f"max |x error| {100 * abs(eb[i, 0]):.1f} cm (t = {t[before][i]:.1f} s, "
               f"{dist[before][i]:.2f} m covered), max |error| {100 * np.nanmax(np.linalg.norm(eb, axis=1)):.1f} cm")
        ax.text(0.01, 0.96, txt, transform=ax.transAxes, ha="left", va="top", fontsize=9,
                bbox=dict(fc="white", ec="0.7", alpha=0.9))
    ax.set_zorder(ax2.get_zorder() + 1)
    ax.patch.set_visible(False)
    return ax2


def odo_ylim(runs):
    lo, hi = -1.0, 1.0
    for r in runs:
        err, _ = odometry(r)
        fall = r.fall_time()
        sel = np.ones(r.n, dtype=bool) if fall is None else (r.t < fall)
        e = 100.0 * err[sel]
        e = e[np.isfinite(e)]
        if e.size:
            lo, hi = min(lo, float(e.min())), max(hi, float(e.max()))
    pad = 0.25 * (hi - lo)
    return lo - pad, hi + 0.6 * pad + 0.12 * (hi - lo)   # room for the note at the top


def fig6_odometry(run, other, out, written):
    runs = [run] if other is None else [other, run]
    fig, axes = plt.subplots(len(runs), 1, figsize=(12, 4.6 * len(runs) + 0.8), sharex=True, squeeze=False)
    axes = axes[:, 0]
    ylim = odo_ylim(runs)
    dmax = max([0.1] + [float(np.nanmax(odometry(r)[1])) for r in runs if r.n])
    dmin = min([0.0] + [float(np.nanmin(odometry(r)[1])) for r in runs if r.n])
    for ax, r in zip(axes, runs):
        ax2 = odo_panel(ax, r, ylim)
        ax2.set_ylim(dmin, dmax * 1.05)
    if other is None:
        axes[0].set_title(run.dir)
        fig.suptitle(f"Fig. 6 - leg-odometry error ({run.label})", fontsize=13)
    else:
        axes[0].set_title(f"upper: {other.label}   ({other.dir})")
        axes[1].set_title(f"lower: {run.label}   ({run.dir})")
        fig.suptitle(f"Fig. 6 - leg-odometry error, {other.recovery} (upper) vs {run.recovery} (lower)",
                     fontsize=13)
    axes[-1].set_xlabel("time [s]")
    tmax = max([float(r.t[-1]) for r in runs if r.n] or [1.0])
    axes[-1].set_xlim(0, tmax)
    h1, l1 = axes[0].get_legend_handles_labels()
    from matplotlib.lines import Line2D
    h1.append(Line2D([], [], color="k", lw=2.0))
    l1.append("covered distance x (right axis)")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.legend(h1, l1, loc="lower center", ncol=4, frameon=False)
    save(fig, os.path.join(out, "fig6_odometry.png"), written)


# ----------------------------------------------------------------------------- fig 7

def cone_violation(run, leg):
    """|F_t| / (mu |F_n|) of the ground-truth force at the true normal, clipped to [0, 1]."""
    F = run.vec("{leg}_force_{c}", leg)
    n = run.vec("{leg}_normal_{c}", leg)
    nn = np.linalg.norm(n, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = n / nn[:, None]
        fn = np.sum(F * n, axis=1)
        ft = np.linalg.norm(F - fn[:, None] * n, axis=1)
        r = ft / (run.d[f"{leg}_mu"] * fn)
    ok = run.contact(leg) & (fn > 1e-6) & (run.d[f"{leg}_mu"] > 0) & np.isfinite(r)
    return masked(np.clip(r, 0.0, 1.0), ok)


def phase_shading(ax, tt, slip_gt, flag, correcting, freeze, labels):
    """Paper-style phases: estimation (flag up, n/mu not yet moving) red, correction blue,
    freeze purple; the ground-truth slip as a dark band along the top edge."""
    lab = (lambda x: x) if labels else (lambda x: None)
    shade_runs(ax, tt, flag & ~correcting, color="#d62728", alpha=0.14, lw=0,
               label=lab("slip flag up, $n,\\mu$ used fixed\n(estimation)"))
    shade_runs(ax, tt, correcting, color="#1f77b4", alpha=0.20, lw=0,
               label=lab("$n$ or $\\mu$ used changing\n(correction)"))
    shade_runs(ax, tt, freeze, color="#9467bd", alpha=0.25, lw=0, label=lab("freeze mode"))
    if slip_gt.any():
        ax.fill_between(tt, 0.93, 1.0, where=slip_gt, step="post", color="0.25", alpha=0.8, lw=0,
                        transform=ax.get_xaxis_transform(), label=lab("true slip (contact, >0.05 m/s)"))


def fig7_normal(run, ev, out, written):
    leg, s, e = ev
    li = LEGS.index(leg)
    t_det = run.t[s]
    w = window(run, t_det, 0.100, max(0.300, run.t[e] - t_det + 0.100))
    tt = 1000.0 * (run.t[w] - t_det)
    flag = run.bits("slip_mask", li)[w]
    slip_gt = run.true_slip(leg)[w]
    freeze = np.zeros(int(np.count_nonzero(w)), dtype=bool)
    fl = run.d["flags"][w]
    ok = np.isfinite(fl)
    freeze[ok] = (fl[ok].astype(np.int64) & FREEZE_BIT) != 0
    stance = run.bits("stance_mask", li)[w]

    n_used = run.vec("normal_used_{leg}_{c}", leg)[w]
    n_hat = run.vec("normal_hat_{leg}_{c}", leg)[w]
    hat_ok = np.linalg.norm(n_hat, axis=1) > 0.5
    n_gt = run.vec("{leg}_normal_{c}", leg)[w]
    con = run.contact(leg)[w]

    # correction phase: the n or mu used by the QP for this leg is moving
    mu_used = run.d[f"mu_used_{leg}"][w]
    dn = np.r_[0.0, np.linalg.norm(np.diff(n_used, axis=0), axis=1)]
    dmu = np.r_[0.0, np.abs(np.diff(mu_used))]
    correcting = (np.nan_to_num(dn) > 1e-6) | (np.nan_to_num(dmu) > 1e-6)

    fig, axes = plt.subplots(4, 1, figsize=(11, 10), sharex=True,
                             gridspec_kw={"height_ratios": [1, 1, 1, 1.25]})
    fig.subplots_adjust(left=0.09, right=0.70, top=0.91, bottom=0.07, hspace=0.12)
    for k, c in enumerate(XYZ):
        ax = axes[k]
        phase_shading(ax, tt, slip_gt, flag, correcting, freeze, labels=(k == 0))
        ax.plot(tt, n_used[:, k], color="#1f77b4", lw=2.0, label="$n$ used by QP")
        ax.plot(tt, masked(n_hat[:, k], hat_ok), color="#d62728", lw=1.4, label="$\\hat n$ estimate")
        ax.plot(tt, masked(n_gt[:, k], con), color="k", lw=1.6, ls="--", label="$n_{gt}$ ground truth")
        ax.set_ylabel(f"$n_{c}$ [-]")
        vals = np.concatenate([n_used[:, k], masked(n_hat[:, k], hat_ok), masked(n_gt[:, k], con)])
        vals = vals[np.isfinite(vals)]
        if vals.size:
            lo, hi = float(vals.min()), float(vals.max())
            pad = max(0.02, 0.12 * (hi - lo))
            ax.set_ylim(lo - pad, hi + pad)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)

    # panel 4: cone violation of the slipping foot + knee torque of a diagonal stance leg
    ax = axes[3]
    phase_shading(ax, tt, slip_gt, flag, correcting, freeze, labels=False)
    viol = cone_violation(run, leg)[w]
    ax.plot(tt, viol, color="#1f77b4", lw=1.8, label=f"cone violation {leg}")
    ax.set_ylim(-0.05, 1.1)
    ax.set_ylabel("$|F_t|/(\\mu\\,F_n)$ [0-1]", color="#1f77b4")
    # diagonal leg, or the other leg most in stance over the window
    diag = DIAGONAL[leg]
    st = {lg: np.count_nonzero(run.bits("stance_mask", j)[w]) for j, lg in enumerate(LEGS)}
    if st[diag] < 0.5 * tt.size:
        others = [lg for lg in LEGS if lg != leg]
        diag = max(others, key=lambda lg: st[lg])
    ax2 = ax.twinx()
    ax2.grid(False)
    tau = run.d[f"tau_{diag}_kfe"][w]
    why = "diagonal" if diag == DIAGONAL[leg] else f"{DIAGONAL[leg]} swings"
    ax2.plot(tt, tau, color="#d62728", lw=1.4, label=f"knee torque {diag} KFE\n(measured; {why})")
    ax2.set_ylabel(f"$\\tau$ {diag} KFE [Nm]", color="#d62728")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, loc="upper left", bbox_to_anchor=(1.13, 1.0), borderaxespad=0.0)
    ax.set_xlabel(f"time from slip detection [ms]  (detection at t = {t_det:.3f} s)")
    ax.set_xlim(tt[0], tt[-1])
    for a in axes:
        a.axvline(0, color="k", lw=0.8, alpha=0.6)
    # stance of the slipping leg, as a note
    td = [1000.0 * (ti - t_det) for ti, evn, lg, _ in run.events
          if lg == leg and evn == "touchdown" and tt[0] <= 1000.0 * (ti - t_det) <= tt[-1]]
    for x in td:
        for a in axes:
            a.axvline(x, color="0.3", lw=0.9, ls=":")
    if td:
        from matplotlib.lines import Line2D
        h, l = axes[0].get_legend_handles_labels()
        axes[0].legend(h + [Line2D([], [], color="0.3", lw=0.9, ls=":")], l + [f"touch-down of {leg}"],
                       loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.suptitle(f"Fig. 7 - slip event of {leg} ({run.label}): {flag_text(run, ev)}\n"
                 f"surface normal, friction-cone violation, stance knee torque", fontsize=12)
    save(fig, os.path.join(out, "fig7_normal.png"), written)
    return diag


# ----------------------------------------------------------------------------- fig 8

def fig8_slip_flags(run, ev, out, written):
    leg, s, e = ev
    t_det = run.t[s]
    w = window(run, t_det, 0.300, max(0.700, run.t[e] - t_det + 0.150))
    tt = 1000.0 * (run.t[w] - t_det)
    fig, (ax, axf) = plt.subplots(2, 1, figsize=(11, 8), sharex=True,
                                  gridspec_kw={"height_ratios": [3, 2]})
    speeds = {}
    stance = {}
    # The detector compares the velocities' parts along the ground (its
    # terrain plane); here: rotated to W by the IMU attitude, horizontal part.
    qw, qx, qy, qz = (run.d[f"imu_q{c}"][w] for c in "wxyz")
    rot = np.stack([
        np.stack([1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)], axis=1),
        np.stack([2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)], axis=1),
    ], axis=1)  # first two rows of R_wb, per tick
    have_attitude = np.isfinite(rot).all()
    for i, lg in enumerate(LEGS):
        u = run.vec("foot_vel_base_{leg}_{c}", lg)[w]
        along = np.einsum("tij,tj->ti", rot, u) if have_attitude else u  # whole vectors without an attitude
        speeds[lg] = np.linalg.norm(along, axis=1)
        stance[lg] = run.bits("stance_mask", i)[w]
    S = np.stack([masked(speeds[lg], stance[lg]) for lg in LEGS], axis=1)
    with np.errstate(all="ignore"):
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med = np.nanmedian(S, axis=1)
    ax.fill_between(tt, np.maximum(med - DETECT_TH, 0), med + DETECT_TH, color="0.5", alpha=0.2, lw=0,
                    label=f"stance median $\\pm$ th ({DETECT_TH:.3f} m/s)")
    ymax = 0.0
    for lg in LEGS:
        col = LEG_COLORS[lg]
        ax.plot(tt, masked(speeds[lg], ~stance[lg]), color=col, lw=0.8, alpha=0.35, ls="--")
        ax.plot(tt, masked(speeds[lg], stance[lg]), color=col, lw=1.8 if lg == leg else 1.3, label=f"{lg}")
        v = masked(speeds[lg], stance[lg])
        if np.any(np.isfinite(v)):
            ymax = max(ymax, float(np.nanmax(v)))
    ax.set_ylim(0, max(0.3, ymax * 1.15))
    ax.set_ylabel("$|u_i|$ along the ground (horizontal in W) [m/s]")
    from matplotlib.lines import Line2D
    h, l = ax.get_legend_handles_labels()
    h.append(Line2D([], [], color="0.4", lw=0.8, ls="--"))
    l.append("swing (not tested)")
    ax.legend(h, l, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)

    # flags as stacked 0/1 steps, ground-truth slip shaded behind them
    gap = 1.5
    for i, lg in enumerate(LEGS):
        base = (len(LEGS) - 1 - i) * gap
        col = LEG_COLORS[lg]
        gt = run.true_slip(lg)[w]
        for a, b in runs_of(gt):
            axf.fill_between([tt[a], tt[b] + 1.0], base - 0.15, base + 1.15, color=col, alpha=0.18, lw=0)
        flag = run.bits("slip_mask", i)[w].astype(float)
        axf.step(tt, base + flag, where="post", color=col, lw=2.0)
    axf.set_yticks([(len(LEGS) - 1 - i) * gap + 0.5 for i in range(len(LEGS))])
    axf.set_yticklabels([f"{lg}" for lg in LEGS])
    axf.set_ylim(-0.4, (len(LEGS) - 1) * gap + 1.4)
    axf.set_ylabel("slip flag (0/1) per leg")
    axf.legend([Line2D([], [], color="0.2", lw=2.0),
                matplotlib.patches.Patch(color="0.5", alpha=0.35)],
               ["controller slip flag", "true slip\n(contact, >0.05 m/s)"],
               loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axf.set_xlabel(f"time from slip detection [ms]  (detection of {leg} at t = {t_det:.3f} s)")
    axf.set_xlim(tt[0], tt[-1])
    for a in (ax, axf):
        a.axvline(0, color="k", lw=0.8, alpha=0.6)
    note = true_slip_note(run, ev)
    fig.suptitle(f"Fig. 8 - slip flags around a slip of {leg} ({run.label})\n{flag_text(run, ev)}{note}",
                 fontsize=12)
    fig.tight_layout()
    save(fig, os.path.join(out, "fig8_slip_flags.png"), written)


# ----------------------------------------------------------------------------- friction map

def mu_colormap():
    """The replay's ground colours: ice blue at mu 0 to earth at 1."""
    from matplotlib.colors import LinearSegmentedColormap
    return LinearSegmentedColormap.from_list(
        "mu", [(0.0, "#cfefff"), (0.3, "#8fb8d8"), (0.7, "#8c8272"), (1.0, "#6b5a46")])


def fig_friction_map(run, out, written):
    """The controller's friction map (friction_map.json): each cell it
    wrote, filled with its estimate and labelled estimate / truth under the
    feet that wrote it, over the true friction, with the base's path."""
    path = os.path.join(run.dir, "friction_map.json")
    if not os.path.isfile(path):
        return
    with open(path) as f:
        m = json.load(f)
    tr, cells, size = m["truth"], m["cells"], m["cell_size"]
    truth = np.array(tr["mu"], dtype=float).reshape(tr["ny"], tr["nx"])
    x0, y0, step = tr["x0"], tr["y0"], tr["step"]
    extent = (x0, x0 + tr["nx"] * step, y0, y0 + tr["ny"] * step)
    width = extent[1] - extent[0]
    height = extent[3] - extent[2]
    fig, ax = plt.subplots(figsize=(min(16.0, 2.0 + 3.2 * width), min(12.0, 1.6 + 3.2 * height)))
    cmap = mu_colormap()
    im = ax.imshow(truth, origin="lower", extent=extent, cmap=cmap, vmin=0.0, vmax=1.0,
                   interpolation="nearest", aspect="equal")
    for c in cells:
        r = matplotlib.patches.Rectangle((c["x"] - size / 2, c["y"] - size / 2), size, size,
                                         fc=cmap(min(max(c["mu"], 0.0), 1.0)), ec="k", lw=1.2)
        ax.add_patch(r)
        ax.text(c["x"], c["y"], f"{c['mu']:.3f}\n({c['true_mu']:.2f})\nn={c['count']}", ha="center",
                va="center", fontsize=7.5, color="k" if c["mu"] < 0.5 else "w")
    ax.plot(run.d["base_pos_x"], run.d["base_pos_y"], color="k", lw=0.8, ls=":", label="base path")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(False)
    fig.colorbar(im, ax=ax, fraction=0.025, pad=0.01, label="$\\mu$ (ground: truth; squares: estimate)")
    err = m.get("error_max_pct")
    ax.set_title(f"Friction map ({run.label}): {len(cells)} cells of {size:g} m, estimate (truth under the "
                 f"feet that wrote it), n estimates; largest error "
                 + (f"{err:.1f} %" if err is not None else "none"), fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    save(fig, os.path.join(out, "fig_friction_map.png"), written)


# ----------------------------------------------------------------------------- main

def load_run(run_dir):
    if not os.path.isfile(os.path.join(run_dir, "log.csv")):
        sys.stderr.write(f"plots.py: no log.csv in {run_dir}\n")
        sys.exit(2)
    return Run(run_dir)


def main(argv=None):
    p = argparse.ArgumentParser(description="Figures 5-8 (Focchi et al.) from a hyq_sim run directory.")
    p.add_argument("run_dir", help="run directory with log.csv, summary.json, events.csv")
    p.add_argument("--compare", metavar="OTHER_RUN_DIR",
                   help="second run (e.g. recovery off) for the upper panel of fig6")
    p.add_argument("--leg", choices=LEGS, help="slip event of figs 7-8: only this leg's flag runs")
    p.add_argument("--t", type=float, metavar="SECONDS",
                   help="slip event of figs 7-8: the flag run nearest to this time")
    a = p.parse_args(argv)

    run = load_run(a.run_dir)
    other = load_run(a.compare) if a.compare else None
    if run.missing:
        print(f"note: {len(run.missing)} column(s) missing from log.csv, plotted as empty: "
              + ", ".join(run.missing[:6]) + (" ..." if len(run.missing) > 6 else ""))
    if run.n == 0:
        print("note: log.csv has no data rows")

    written = []
    fig5_mu(run, a.run_dir, written)
    fig6_odometry(run, other, a.run_dir, written)
    fig_friction_map(run, a.run_dir, written)
    ev = pick_slip(run, a.leg, a.t) if run.n else None
    if ev is None and a.t is not None and run.n:
        # no flag run: centre the window on the requested time, on the requested leg (or LF)
        k = int(np.clip(np.searchsorted(run.t, a.t), 0, run.n - 1))
        ev = (a.leg or "LF", k, k, "requested time, no flag")
        print(f"note: no slip flag{' of ' + a.leg if a.leg else ''}; figs 7-8 centred on t = {run.t[k]:.3f} s")
    if ev is None:
        print(f"note: no slip flag{' of ' + a.leg if a.leg else ''} in this run: fig7/fig8 skipped")
    else:
        leg, s, e, why = ev
        ev = (leg, s, e)
        print(f"slip event for fig7/fig8: {leg}, flag {run.t[s]:.3f}-{run.t[e]:.3f} s ({why})")
        fig7_normal(run, ev, a.run_dir, written)
        fig8_slip_flags(run, ev, a.run_dir, written)
    for w in written:
        print(w)
    return 0


if __name__ == "__main__":
    sys.exit(main())
