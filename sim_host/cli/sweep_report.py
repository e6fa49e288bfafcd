#!/usr/bin/env python3
"""The aggregate of a sweep's folder (written by `hyq_sim sweep`): sweep.csv
(one row per case), sweep.json (each group's success rate and the
distribution of its figures, the cases that crashed or timed out) and plots/.

A group is one parameter combination on one engine with recovery on or off;
its runs are its seeds. A run succeeds when it ran to its end without
falling (and, if the sweep names goal_distance_m, walked that far).

    python3 sim_host/cli/sweep_report.py out/sweeps/<name> [--quiet] [--json] [--no-plots]

Exit status: 0 when every case ran to its end, 1 when some case failed,
crashed, timed out or has not run, 2 when the folder is damaged (a file of a
case that is not a regular file, too large, or not what the simulator writes:
one line on stderr names the file and what is wrong with it).
"""
import argparse
import csv
import io
import json
import math
import os
import stat
import statistics
import sys

# [bytes] the most the report reads of each file: a summary.json is a few
# KB, an exit_code a few bytes; cases.csv has a row per case (at most
# 10,000, with their set values).
MAX_SUMMARY_BYTES = 1 << 20
MAX_EXIT_CODE_BYTES = 64
MAX_META_BYTES = 1 << 20
MAX_CASES_CSV_BYTES = 64 << 20
RUN_LOG_TAIL_BYTES = 64 << 10


class Damaged(Exception):
    """A file of the sweep's folder the report cannot take: its message is
    "<path>: <what is wrong>", one line."""


def _kind(mode):
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a plain file"


def read_bounded(path, limit, tail=False):
    """The bytes of the regular file `path`: at most `limit` of them (the
    last ones with `tail`), else Damaged. Opened without blocking, so that a
    FIFO is refused, never waited on; FileNotFoundError passes through."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise Damaged(f"{path}: not a regular file ({_kind(st.st_mode)})")
        if tail and st.st_size > limit:
            os.lseek(fd, st.st_size - limit, os.SEEK_SET)
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, min(1 << 16, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > limit and not tail:
            raise Damaged(f"{path}: too large: more than {limit} bytes")
        return b"".join(chunks)[-limit:] if tail else b"".join(chunks)
    finally:
        os.close(fd)


def _finite_float(text):
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:40]} is out of range")
    return value


def _refuse_constant(name):
    raise ValueError(f"{name} is not a number")


def read_json(path, limit):
    """The JSON document in `path` (numbers finite), else Damaged."""
    try:
        text = read_bounded(path, limit).decode("utf-8")
    except UnicodeDecodeError as e:
        raise Damaged(f"{path}: not UTF-8 text (byte {e.start})") from None
    except OSError as e:
        raise Damaged(f"{path}: {e.strerror}") from None
    try:
        return json.loads(text, parse_float=_finite_float, parse_constant=_refuse_constant)
    except json.JSONDecodeError as e:
        raise Damaged(f"{path}: not JSON: {e.msg} (line {e.lineno}, column {e.colno})") from None
    except (ValueError, RecursionError) as e:
        raise Damaged(f"{path}: not JSON the simulator writes: {str(e)[:200]}") from None


def is_number(v):
    """A finite int or float (bool is not a number here)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(float(v))
    except OverflowError:
        return False

# Figures per run, from summary.json: (column, unit, getter).
def _get(path):
    def get(summary):
        v = summary
        for k in path:
            if v is None:
                return None
            v = v[k] if isinstance(k, int) else v.get(k)
        return v
    return get


def _odometry_per_50cm_cm(s):
    walked = s.get("distance_walked_m") or 0.0
    return 100.0 * s["odometry_error_m"]["max"] * 0.5 / walked if walked > 0 else None


def _missed_over_5mm(s):
    r = s.get("recall_by_travel") or []
    return r[0]["events"] - r[0]["detected"] if r else None


FIGURES = [
    ("distance_m", "m", _get(["distance_m"])),
    ("slip_events", "", _get(["slip_events"])),
    ("false_detections", "", _get(["false_detections"])),
    ("false_detections_in_air", "", _get(["false_detections_in_air"])),
    ("missed_slips", "", _get(["missed_slips"])),
    ("missed_over_5mm", "", _missed_over_5mm),
    ("latency_median_ms", "ms", _get(["detection_latency_ms", "median"])),
    ("latency_max_ms", "ms", _get(["detection_latency_ms", "max"])),
    ("after_detection_median_ms", "ms", _get(["slip_duration_after_detection_ms", "median"])),
    ("after_detection_max_ms", "ms", _get(["slip_duration_after_detection_ms", "max"])),
    ("longest_after_detection_path_mm", "mm", _get(["longest_slip_after_detection", "path_mm"])),
    ("longest_after_detection_net_mm", "mm", _get(["longest_slip_after_detection", "net_mm"])),
    ("loaded_after_detection_max_ms", "ms", _get(["loaded_slide_after_detection_ms", "max"])),
    ("mu_error_max_pct", "%", _get(["mu_estimate_error_pct", "max"])),
    ("normal_error_max_deg", "deg", _get(["normal_error_deg", "max"])),
    ("normal_in_use_error_max_deg", "deg", _get(["normal_in_use_error_deg", "max"])),
    ("odometry_per_50cm_cm", "cm", _odometry_per_50cm_cm),
    ("torque_step_max_nm", "N m", _get(["max_stance_torque_step_nm"])),
    ("freeze_events", "", _get(["freeze_events"])),
    ("wall_time_s", "s", _get(["wall_time_s"])),
    ("cpu_time_s", "s", _get(["cpu_time_s"])),
]
# The distributions sweep.json and the plots show.
DISTRIBUTIONS = ["latency_median_ms", "latency_max_ms", "after_detection_max_ms", "loaded_after_detection_max_ms",
                 "mu_error_max_pct",
                 "normal_error_max_deg", "odometry_per_50cm_cm", "distance_m"]


def case_status(case_dir, timeout_s):
    """ok | failed | crashed | timeout | pending, and the exit code (None if
    pending). exit_code holds "<status> <seconds>" (timeout(1)'s codes: 124
    timed out, 128 + n killed by signal n; 137 also after timeout's KILL,
    told apart by the time). One that cannot be read as a file is Damaged."""
    path = os.path.join(case_dir, "exit_code")
    try:
        fields = read_bounded(path, MAX_EXIT_CODE_BYTES).split()
        code = int(fields[0])
        seconds = float(fields[1]) if len(fields) > 1 else 0.0
    except FileNotFoundError:
        return "pending", None
    except OSError as e:
        raise Damaged(f"{path}: {e.strerror}") from None
    except (ValueError, IndexError):
        return "pending", None
    if code == 0:
        return ("ok" if os.path.exists(os.path.join(case_dir, "summary.json")) else "failed"), code
    if code == 124 or (code == 137 and seconds >= timeout_s):
        return "timeout", code
    if code > 128:
        return "crashed", code
    return "failed", code


def last_line(path):
    """The last non-empty line of the end of a run's log ("" if none)."""
    try:
        text = read_bounded(path, RUN_LOG_TAIL_BYTES, tail=True).decode("utf-8", errors="replace")
    except (OSError, Damaged):
        return ""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    return lines[-1][:200] if lines else ""


def read_summary(path):
    """A case's summary.json, checked: fell a bool, distance_m a number,
    fall_time_s a number or null, every figure a number or absent."""
    s = read_json(path, MAX_SUMMARY_BYTES)
    if not isinstance(s, dict):
        raise Damaged(f"{path}: expected a JSON object, got {type(s).__name__}")
    for key in ("fell", "fall_time_s", "distance_m"):
        if key not in s:
            raise Damaged(f"{path}: {key}: missing")
    if not isinstance(s["fell"], bool):
        raise Damaged(f"{path}: fell: expected true or false, got {json.dumps(s['fell'])[:40]}")
    if not is_number(s["distance_m"]):
        raise Damaged(f"{path}: distance_m: expected a finite number, got {json.dumps(s['distance_m'])[:40]}")
    if s["fall_time_s"] is not None and not is_number(s["fall_time_s"]):
        raise Damaged(f"{path}: fall_time_s: expected a finite number or null")
    figures = {}
    for name, _, get in FIGURES:
        try:
            v = get(s)
        except (TypeError, KeyError, IndexError, AttributeError, ZeroDivisionError):
            raise Damaged(f"{path}: {name}: not the structure the simulator writes") from None
        if v is not None and not is_number(v):
            raise Damaged(f"{path}: {name}: expected a finite number, got {json.dumps(v)[:40]}")
        figures[name] = v
    return s, figures


def load_cases(folder, meta):
    rows = []
    path = os.path.join(folder, "cases.csv")
    text = read_bounded(path, MAX_CASES_CSV_BYTES).decode("utf-8", errors="replace")
    for c in csv.DictReader(io.StringIO(text, newline="")):
        d = os.path.join(folder, "cases", c["id"])
        status, code = case_status(d, meta["timeout_s"])
        row = {"id": c["id"], "point": int(c["point"]), "engine": c["engine"], "recovery": c["recovery"],
               "seed": int(c["seed"])}
        for k in meta["set_keys"]:
            row[k] = c[k]
        row.update({"status": status, "exit_code": code, "fell": None, "fall_time_s": None,
                    "goal_reached": None, "success": False})
        for name, _, _ in FIGURES:
            row[name] = None
        if status == "ok":
            s, figures = read_summary(os.path.join(d, "summary.json"))
            row["fell"] = s["fell"]
            row["fall_time_s"] = s["fall_time_s"]
            row.update(figures)
            goal = meta.get("goal_distance_m")
            row["goal_reached"] = None if goal is None else (not s["fell"] and s["distance_m"] >= goal)
            row["success"] = not s["fell"] and row["goal_reached"] is not False
        elif status != "pending":
            row["error"] = last_line(os.path.join(d, "run.log"))
        rows.append(row)
    return rows


def read_meta(folder):
    """sweep_meta.json, checked (the sweep writes it before the report)."""
    path = os.path.join(folder, "sweep_meta.json")
    try:
        meta = read_json(path, MAX_META_BYTES)
    except FileNotFoundError:
        raise Damaged(f"{folder}: not a sweep's folder (no sweep_meta.json)") from None
    ok = (isinstance(meta, dict) and isinstance(meta.get("name"), str) and isinstance(meta.get("scenario"), str)
          and is_number(meta.get("timeout_s")) and isinstance(meta.get("set_keys"), list)
          and all(isinstance(k, str) for k in meta["set_keys"])
          and (meta.get("goal_distance_m") is None or is_number(meta.get("goal_distance_m"))))
    if not ok:
        raise Damaged(f"{path}: not what hyq_sim sweep writes (name, scenario, timeout_s, set_keys)")
    return meta


def dist(xs):
    xs = sorted(x for x in xs if x is not None)
    if not xs:
        return None
    p90 = xs[min(len(xs) - 1, int(math.ceil(0.9 * len(xs))) - 1)]
    return {"n": len(xs), "median": statistics.median(xs), "p90": p90, "max": xs[-1], "min": xs[0]}


def groups_of(rows, meta):
    keys = []
    by = {}
    for r in rows:
        k = (r["point"], r["engine"], r["recovery"])
        if k not in by:
            by[k] = []
            keys.append(k)
        by[k].append(r)
    out = []
    for k in keys:
        runs = by[k]
        done = [r for r in runs if r["status"] == "ok"]
        g = {"point": k[0], "values": {key: runs[0][key] for key in meta["set_keys"]}, "engine": k[1],
             "recovery": k[2], "runs": len(runs), "completed": len(done),
             "fell": sum(1 for r in done if r["fell"]),
             "goal_reached": (None if meta.get("goal_distance_m") is None
                              else sum(1 for r in done if r["goal_reached"])),
             "success": sum(1 for r in runs if r["success"]),
             "not_completed": [{"id": r["id"], "status": r["status"], "exit_code": r["exit_code"],
                                "error": r.get("error", "")} for r in runs if r["status"] != "ok"],
             "seeds_fell": [r["seed"] for r in done if r["fell"]]}
        g["success_rate"] = g["success"] / g["runs"] if g["runs"] else None
        g["distributions"] = {name: dist(r[name] for r in done) for name in DISTRIBUTIONS}
        g["false_detections"] = sum(r["false_detections"] or 0 for r in done)
        g["false_detections_in_air"] = sum(r["false_detections_in_air"] or 0 for r in done)
        g["missed_over_5mm"] = sum(r["missed_over_5mm"] or 0 for r in done)
        out.append(g)
    return out


def write_csv(folder, rows, meta):
    cols = ["id", "point", "engine", "recovery", "seed"] + meta["set_keys"] + \
        ["status", "exit_code", "fell", "fall_time_s", "goal_reached", "success"] + [f[0] for f in FIGURES]
    tmp = os.path.join(folder, "sweep.csv.tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(cols)
        for r in rows:
            w.writerow(["" if r.get(c) is None else r.get(c) for c in cols])
    os.replace(tmp, os.path.join(folder, "sweep.csv"))


def fmt(x, digits=1):
    return "-" if x is None else f"{x:.{digits}f}"


def table(groups, meta):
    keys = meta["set_keys"]
    head = keys + ["engine", "recovery", "runs", "fell", "success", "not run to end",
                   "latency med/max ms", "after det. max ms", "mu err max %", "odometry /50cm cm"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for g in groups:
        d = g["distributions"]

        def medmax(name, digits=1):
            x = d[name]
            return "-" if x is None else f"{fmt(x['median'], digits)} / {fmt(x['max'], digits)}"
        cells = [g["values"][k] for k in keys] + [
            g["engine"], g["recovery"], str(g["runs"]), str(g["fell"]),
            f"{g['success']}/{g['runs']} ({100.0 * g['success_rate']:.0f} %)",
            str(len(g["not_completed"])),
            "-" if d["latency_median_ms"] is None else
            f"{fmt(d['latency_median_ms']['median'], 0)} / {fmt(d['latency_max_ms']['max'], 0)}",
            "-" if d["after_detection_max_ms"] is None else fmt(d["after_detection_max_ms"]["max"], 0),
            medmax("mu_error_max_pct"), medmax("odometry_per_50cm_cm", 2)]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plots(folder, groups, meta):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return "matplotlib not found: no plots"
    out = os.path.join(folder, "plots")
    os.makedirs(out, exist_ok=True)

    def label(g):
        v = ", ".join(f"{k.split('.')[-1]}={g['values'][k]}" for k in meta["set_keys"])
        return (v + "\n" if v else "") + f"{g['engine']} {g['recovery']}"

    colours = {"on": "tab:blue", "off": "tab:orange"}
    # Success rate per group (at most 60 groups are labelled, the figure at
    # most 40 inches wide).
    labelled = len(groups) <= 60
    fig, ax = plt.subplots(figsize=(min(40, max(6, 0.9 * len(groups) + 2)), 3.4))
    ax.bar(range(len(groups)), [100.0 * g["success_rate"] for g in groups],
           color=[colours.get(g["recovery"], "grey") for g in groups])
    if labelled:
        for i, g in enumerate(groups):
            ax.text(i, 100.0 * g["success_rate"] + 1, f"{g['success']}/{g['runs']}", ha="center", fontsize=8)
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels([label(g) for g in groups], fontsize=7)
    else:
        ax.set_xlabel("group (sweep.json's order)")
    ax.set_ylabel("success [%]")
    ax.set_ylim(0, 110)
    ax.set_title(f"{meta['name']}\nruns to the end without a fall"
                 + (f", {meta['goal_distance_m']:g} m walked" if meta.get("goal_distance_m") is not None else ""),
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "success.png"), dpi=110)
    plt.close(fig)

    # The figures' distributions over the runs of each group.
    rows = load_cases(folder, meta)
    names = [n for n in DISTRIBUTIONS if any(g["distributions"][n] for g in groups)] if labelled else []
    units = {f[0]: f[1] for f in FIGURES}
    if names:
        cols = 3
        nrows = (len(names) + cols - 1) // cols
        fig, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 2.8 * nrows), squeeze=False)
        for ax, name in zip(axes.flat, names):
            data, labels, cs = [], [], []
            for g in groups:
                xs = [r[name] for r in rows if r["status"] == "ok" and r[name] is not None and
                      (r["point"], r["engine"], r["recovery"]) == (g["point"], g["engine"], g["recovery"])]
                data.append(xs if xs else [float("nan")])
                labels.append(label(g))
                cs.append(colours.get(g["recovery"], "grey"))
            parts = ax.boxplot(data, patch_artist=True, widths=0.6)
            for patch, c in zip(parts["boxes"], cs):
                patch.set_facecolor(c)
                patch.set_alpha(0.5)
            ax.set_xticks(range(1, len(labels) + 1))
            ax.set_xticklabels(labels, fontsize=6)
            ax.set_title(f"{name} [{units[name]}]" if units[name] else name, fontsize=8)
        for ax in list(axes.flat)[len(names):]:
            ax.axis("off")
        fig.tight_layout()
        fig.savefig(os.path.join(out, "distributions.png"), dpi=110)
        plt.close(fig)
    return f"plots in {out}/"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--elapsed", type=float, default=None, help="seconds the sweep's last start took")
    ap.add_argument("--ran", type=int, default=None, help="cases its last start ran")
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--no-plots", action="store_true")
    a = ap.parse_args()
    folder = os.path.abspath(a.folder)
    try:
        return report(folder, a)
    except Damaged as e:
        # Nothing is written: the aggregate of an earlier report stays.
        print(f"sweep_report: {str(e).splitlines()[0] if str(e) else 'damaged folder'}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"sweep_report: {e.filename or folder}: {e.strerror}", file=sys.stderr)
        return 1


def report(folder, a):
    """Reads the folder's cases and writes sweep.json, sweep.csv and the
    plots; the exit status."""
    meta = read_meta(folder)
    rows = load_cases(folder, meta)
    groups = groups_of(rows, meta)
    counts = {s: sum(1 for r in rows if r["status"] == s) for s in ("ok", "failed", "crashed", "timeout", "pending")}
    report = {"name": meta["name"], "scenario": meta["scenario"], "set_keys": meta["set_keys"],
              "goal_distance_m": meta.get("goal_distance_m"), "cases": len(rows), "status": counts,
              "last_start": {"elapsed_s": a.elapsed, "cases_run": a.ran},
              "case_cpu_time_s": sum(r["cpu_time_s"] or 0.0 for r in rows),
              "groups": groups}
    tmp = os.path.join(folder, "sweep.json.tmp")
    with open(tmp, "w") as f:
        json.dump(report, f, indent=1)
        f.write("\n")
    os.replace(tmp, os.path.join(folder, "sweep.json"))
    write_csv(folder, rows, meta)
    plot_note = ""
    if not a.no_plots:
        try:
            plot_note = plots(folder, groups, meta)
        except Exception as e:  # the figures only: sweep.json and sweep.csv are written
            plot_note = f"no plots ({type(e).__name__}: {str(e).splitlines()[0][:200] if str(e) else ''})"

    if a.json:
        print(json.dumps({k: report[k] for k in ("name", "cases", "status", "last_start")} |
                         {"groups": [{k: g[k] for k in ("values", "engine", "recovery", "runs", "fell",
                                                        "success", "success_rate")} for g in groups]}))
    elif not a.quiet:
        took = "" if a.elapsed is None else f"; this start ran {a.ran} cases in {a.elapsed:.0f} s"
        print(f"sweep {meta['name']}: {len(rows)} cases: {counts['ok']} ran to the end, {counts['failed']} failed, "
              f"{counts['crashed']} crashed, {counts['timeout']} timed out, {counts['pending']} not run{took}")
        print(table(groups, meta))
        for g in groups:
            for c in g["not_completed"]:
                if c["status"] != "pending":
                    print(f"  {c['id']}: {c['status']} (exit {c['exit_code']}) {c['error']}")
        print(f"{folder}/sweep.json, sweep.csv" + (f"; {plot_note}" if plot_note else ""))
    ok = counts["ok"] == len(rows)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
