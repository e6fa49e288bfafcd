#!/usr/bin/env python3
"""The controller on the hyq plant: the real-plant table and the margin map.

    make real-plant                      # = python3 docs/real_plant.py --run
    python3 docs/real_plant.py [--run] [--wide] [--terrain] [--fresh] [--jobs N] [--sim PATH]
                               [--out-dir DIR] [--output FILE]

With --run, runs through `hyq_sim sweep` (docs/sweeps.md), into
out/real_plant/ (--out-dir):

  - the real-plant table: each scenario of SCENARIOS on the ideal and the
    hyq plant (`set: {plant.model: [ideal, hyq]}`), recovery on and off,
    ODE seeds 1-8 and MuJoCo seeds 1-4 (sweep files written to
    out/real_plant/sweeps/);
  - the margin map: sim_host/sweeps/margin_actuator_{ice_patches,ramp}.yaml
    (torque-loop bandwidth x transport delay) and
    margin_trunk_{ice_patches,ramp}.yaml (trunk mass x inertia over the
    published body's), seeds 1-4, recovery on and off.

With --wide, runs every scenario of SCENARIOS on the hyq plant alone over
seeds 1-32, recovery on and off, on ODE and on MuJoCo (about 50 minutes
on two cores), for the section's seeds 1-32 table.

With --terrain, runs the drawn terrain sets (sim_host/sweeps/terrain_*.yaml:
the validation and test sets, 256 terrains each on ODE and the first 64 on
MuJoCo, the hyq plant, recovery on and off) into out/real_plant/ and writes
the section between the terrain markers.

A sweep whose sweep.json exists is not run again unless --fresh. Then it
reads the sweeps' sweep.json, draws docs/figures/margin_*.png and writes the
section between the real-plant markers of --output (default
docs/results.md; `make results` keeps that section as it is). Needs
python3-matplotlib for the figures.
"""

import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BEGIN = "<!-- real-plant:begin (docs/real_plant.py) -->"
END = "<!-- real-plant:end -->"
TERRAIN_BEGIN = "<!-- terrain:begin (docs/real_plant.py) -->"
TERRAIN_END = "<!-- terrain:end -->"
TERRAIN_SETS = ["terrain_validation", "terrain_test", "terrain_validation_mujoco", "terrain_test_mujoco"]

# (scenario, goal distance [m] or None): crossing goals as in docs/results.py.
SCENARIOS = [
    ("flat", None), ("ice_patches", 3.77), ("ramp", 3.4), ("stance_slip", None), ("two_feet_ice", None),
    ("ice_to_grip", None), ("ice_010", 3.77), ("ramp_035", None), ("trot_flat", None),
    ("trot_ice_patches", None), ("trot_ramp", None), ("trot_push_ice", None), ("trot_ice_fast", None),
    ("crawl_to_trot", None),
]
ODE_SEEDS = (1, 8)
MUJOCO_SEEDS = (1, 4)
WIDE_SEEDS = (1, 32)  # --wide: the hyq plant alone, both engines
MARGIN_SEEDS = 4  # the margin map's sweeps run seeds 1-4
MARGIN = ["margin_actuator_ice_patches", "margin_actuator_ramp", "margin_trunk_ice_patches", "margin_trunk_ramp"]


def sweep_file(out_dir, scenario, goal, engine, seeds, plants="ideal, hyq", suffix=""):
    name = f"{scenario}_{engine}{suffix}"
    path = os.path.join(out_dir, "sweeps", f"{name}.yaml")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    text = (f"name: {name}\n"
            f"scenario: {os.path.join(ROOT, 'sim_host', 'scenarios', scenario + '.yaml')}\n"
            f"seeds: {{from: {seeds[0]}, to: {seeds[1]}}}\n"
            f"recovery: [on, off]\nengines: [{engine}]\n"
            + (f"goal_distance_m: {goal}\n" if goal else "")
            + f"set:\n  plant.model: [{plants}]\n")
    with open(path, "w") as f:
        f.write(text)
    return path


def run_sweep(sim, path, out, jobs, fresh):
    if not fresh and os.path.exists(os.path.join(out, "sweep.json")):
        return
    args = [sim, "sweep", path, "--jobs", str(jobs), "--out", out, "--quiet"]
    if fresh and os.path.exists(out):
        args.append("--fresh")
    print("running", os.path.relpath(path, ROOT), flush=True)
    subprocess.run(args, check=True)


def groups(out):
    path = os.path.join(out, "sweep.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)["groups"]


def worst(group, key):
    d = group["distributions"].get(key)
    return None if not d or d.get("max") is None else d["max"]


def fmt(v, digits=0):
    return "-" if v is None else f"{v:.{digits}f}"


def cell(group):
    """falls, successes/runs, longest slip after detection (and loaded slide), mu error max, false
    detections."""
    if group is None:
        return ["", "", "", "", ""]
    success = f"{group['success']}/{group['runs']}" if group.get("goal_reached") is not None else "-"
    after = fmt(worst(group, "after_detection_max_ms"))
    loaded = worst(group, "loaded_after_detection_max_ms")
    if loaded is not None and after != "-":
        after += f" ({fmt(loaded)})"
    return [f"{group['fell']}/{group['runs']}", success, after,
            fmt(worst(group, "mu_error_max_pct"), 1), str(group["false_detections"])]


def plant_table(out_dir, engine, seeds):
    head = ("| scenario | recovery | ideal: falls | crossed | after det. max ms (loaded) | mu err max % | false "
            "| hyq: falls | crossed | after det. max ms (loaded) | mu err max % | false |")
    rows = [head, "|" + "---|" * 12]
    for scenario, _ in SCENARIOS:
        gs = groups(os.path.join(out_dir, f"{scenario}_{engine}"))
        if gs is None:
            continue
        for recovery in ("on", "off"):
            by_plant = {g["values"]["plant.model"]: g for g in gs if g["recovery"] == recovery}
            rows.append(f"| {scenario} | {recovery} | " + " | ".join(cell(by_plant.get("ideal"))) + " | " +
                        " | ".join(cell(by_plant.get("hyq"))) + " |")
    return rows


def wide_table(out_dir):
    """The hyq plant over WIDE_SEEDS on both engines: per scenario and recovery setting, falls,
    crossings, the longest slip after detection (and loaded slide), the runs over 40 ms by each,
    slips of 5 mm or more missed, mu error max, false detections."""
    import csv
    engines = ("ode", "mujoco")
    head = ("| scenario | recovery | " + " | ".join(
        f"{e}: falls | crossed | after det. max ms (loaded) | runs over 40 ms (loaded) | missed over 5 mm "
        f"| mu err max % | false" for e in ("ODE", "MuJoCo")) + " |")
    rows = [head, "|" + "---|" * 16]
    found = False
    for scenario, _ in SCENARIOS:
        cells = {}
        for engine in engines:
            path = os.path.join(out_dir, f"{scenario}_{engine}_wide", "sweep.csv")
            if os.path.exists(path):
                with open(path) as f:
                    cells[engine] = [c for c in csv.DictReader(f) if c["status"] == "ok"]
        if not cells:
            continue
        found = True
        for recovery in ("on", "off"):
            out = [scenario, recovery]
            for engine in engines:
                runs = [c for c in cells.get(engine, []) if c["recovery"] == recovery]
                if not runs:
                    out += [""] * 7
                    continue

                def values(key):
                    return [float(c[key]) for c in runs if c[key] not in ("", None)]

                after, loaded = values("after_detection_max_ms"), values("loaded_after_detection_max_ms")
                crossed = (f"{sum(c['success'] == 'True' for c in runs)}/{len(runs)}"
                           if runs[0]["goal_reached"] != "" else "-")
                over = f"{sum(a > 40.0 for a in after)} ({sum(a > 40.0 for a in loaded)})"
                top = "-" if not after else f"{fmt(max(after))} ({fmt(max(loaded) if loaded else None)})"
                mu = values("mu_error_max_pct")
                out += [f"{sum(c['fell'] == 'True' for c in runs)}/{len(runs)}", crossed, top, over,
                        str(sum(int(float(c["missed_over_5mm"] or 0)) for c in runs)),
                        fmt(max(mu) if mu else None, 1), str(sum(int(float(c["false_detections"] or 0)) for c in runs))]
            rows.append("| " + " | ".join(out) + " |")
    return rows if found else []


def delay_label(text):
    # "{sensor_ticks: 2, command_ticks: 2, imu_ticks: 3}" -> "2"
    return text.split("sensor_ticks:")[1].split(",")[0].strip()


MAPS = {
    "actuator": ("plant.actuator.bandwidth", "plant.delay", "torque-loop bandwidth [Hz]",
                 "transport delay each way [ticks]", delay_label),
    "trunk": ("plant.trunk_mass_scale", "plant.trunk_inertia_scale", "trunk mass / published",
              "trunk inertia / published", str),
}


def grid(gs, kind, recovery):
    xkey, ykey, _, _, ylabel = MAPS[kind]
    xs, ys, cells = [], [], {}
    for g in gs:
        if g["recovery"] != recovery:
            continue
        x, y = float(g["values"][xkey]), ylabel(g["values"][ykey])
        if x not in xs:
            xs.append(x)
        if y not in ys:
            ys.append(y)
        cells[(x, y)] = g
    return sorted(xs), ys, cells


def draw(out_dir, name, kind, figure_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    gs = groups(os.path.join(out_dir, name))
    if gs is None:
        return None
    _, _, xname, yname, _ = MAPS[kind]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    for ax, recovery in zip(axes, ("on", "off")):
        xs, ys, cells = grid(gs, kind, recovery)
        data = [[min(worst(cells[(x, y)], "after_detection_max_ms") or 0.0, 1000.0) for x in xs] for y in ys]
        im = ax.imshow(data, origin="lower", cmap="viridis_r", vmin=0, vmax=1000, aspect="auto")
        for i, y in enumerate(ys):
            for j, x in enumerate(xs):
                g = cells[(x, y)]
                a = worst(g, "after_detection_max_ms")
                ax.text(j, i, f"{g['fell']}/{g['runs']} fell\n{fmt(a)} ms", ha="center", va="center", fontsize=7,
                        color="white" if (a or 0) > 500 else "black")
        ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs])
        ax.set_yticks(range(len(ys)), ys)
        ax.set_xlabel(xname)
        ax.set_ylabel(yname)
        ax.set_title(f"recovery {recovery}")
    fig.colorbar(im, ax=axes, label="longest slip after detection [ms] (1000: 1000 or more)")
    scenario = name.split("_", 2)[2]
    fig.suptitle(f"{scenario}, hyq plant, seeds 1-{MARGIN_SEEDS}: falls and longest slip after detection"
                 + (" over the torque-loop bandwidth and delay" if kind == "actuator" else
                    " over the trunk's mass and inertia"))
    os.makedirs(figure_dir, exist_ok=True)
    path = os.path.join(figure_dir, f"{name}.png")
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def margin_table(out_dir, name, kind):
    gs = groups(os.path.join(out_dir, name))
    if gs is None:
        return []
    rows = []
    for recovery in ("on", "off"):
        xs, ys, cells = grid(gs, kind, recovery)
        _, _, xname, yname, _ = MAPS[kind]
        rows += [f"Recovery {recovery}: falls of {MARGIN_SEEDS} / longest slip after detection [ms] / mu error max [%]; "
                 f"columns {xname}, rows {yname}.", "",
                 "| " + yname + " | " + " | ".join(f"{x:g}" for x in xs) + " |", "|" + "---|" * (len(xs) + 1)]
        for y in ys:
            rows.append(f"| {y} | " + " | ".join(
                f"{cells[(x, y)]['fell']} / {fmt(worst(cells[(x, y)], 'after_detection_max_ms'))} / "
                f"{fmt(worst(cells[(x, y)], 'mu_error_max_pct'))}" for x in xs) + " |")
        rows.append("")
    return rows


def section(out_dir, figure_dir):
    out = [BEGIN, "",
           "## On the real plant",
           "",
           "The same scenarios on the ideal plant and on the hyq plant (`plant: {model: hyq}`: HyQ's",
           "joints behind their 40 Hz torque loop and 12 rad/s valve limit, one tick of delay each way",
           "and two for the IMU, quantised and differentiated encoders, the IMU where the robot has it,",
           "the published description's bodies; docs/scenarios.md, \"The plant\"), recovery on and off.",
           "The controller",
           "is the same code; on the hyq plant it is configured for the torque loop",
           "(`controller.joint.torque_bandwidth` 40 Hz: docs/design-notes.md, \"Joints behind a torque",
           "loop\"), its crawl's body shift is bounded at 1 m/s^2 (`gait.max_shift_acceleration`:",
           "\"The crawl's margin against a CoM the model misplaces\"), its crawl swings its hind feet 6 cm",
           "high instead of 10 (`gait.step_height`: \"A crawl's landing behind the torque loop\"; the front",
           "feet keep 10: \"The front feet swing high, the hind feet low\"), its trot stands on a diagonal",
           "pair for 0.18 s instead of 0.24 (`gait.trot.duty_factor` 0.7: \"The trot's diagonal stance",
           "behind the torque loop\") and guesses a flagged landing foot down at once",
           "(`gait.trot.guess_delay` 0: \"The trot's guess delay on the hyq plant\"), it takes its",
           "IMU's lever arm out (`controller.estimator.",
           "imu_position`: \"The IMU's lever arm\"), and its crawl starts a loaded stance foot's guess",
           "at the foot's force ratio (\"A loaded stance slide on the hyq plant starts its guess at its",
           "force ratio\"). Made by `make real-plant`",
           "(`python3 docs/real_plant.py --run`).",
           "",
           "\"After det. max\" is the longest slip after detection over the seeds; in brackets the longest",
           "loaded slide after detection (docs/metrics.md): how long a foot went on sliding on the friction",
           "cone under at least 50 N once flagged. The rest of a slip above 0.05 m/s is the contact's",
           "elastic deflection while the force changes fast, or a foot the recovery has unloaded creeping",
           "at a few N (ODE `ice_patches` on the hyq plant: 25-26 ms of slip after detection per run, all",
           "of it loaded).",
           "",
           f"### ODE, seeds {ODE_SEEDS[0]}-{ODE_SEEDS[1]}",
           "",
           *plant_table(out_dir, "ode", ODE_SEEDS),
           "",
           f"### MuJoCo, seeds {MUJOCO_SEEDS[0]}-{MUJOCO_SEEDS[1]}",
           "",
           *plant_table(out_dir, "mujoco", MUJOCO_SEEDS),
           ""]
    wide = wide_table(out_dir)
    if wide:
        out += [f"### The hyq plant, seeds {WIDE_SEEDS[0]}-{WIDE_SEEDS[1]}, both engines",
                "",
                "The same scenarios on the hyq plant alone, over more seeds. \"Loaded\": the loaded slide after",
                "detection (docs/metrics.md: the foot sliding on the friction cone under at least 50 N).",
                "Made by `python3 docs/real_plant.py --wide`.",
                "",
                *wide,
                ""]
    out += [
           "## The margin map",
           "",
           f"Where the controller's margin ends on the hyq plant: `ice_patches` and `ramp`, seeds 1-{MARGIN_SEEDS},",
           "recovery on and off, over the joints' torque-loop bandwidth against the transport delay",
           "(sensor frames and commands d ticks each way, the IMU d + 1), and over the simulated",
           "trunk's mass and inertia against the published description's (the controller's model and",
           f"its 40 Hz configuration unchanged). Each heat-map cell: falls of {MARGIN_SEEDS} and the longest",
           f"slip after detection over the {MARGIN_SEEDS} runs; the tables add the largest mu error. Made by `hyq_sim sweep sim_host/sweeps/margin_<axes>_<scenario>.yaml`",
           "(`make real-plant` runs the four).",
           ""]
    for name in MARGIN:
        kind = "actuator" if "actuator" in name else "trunk"
        png = draw(out_dir, name, kind, figure_dir)
        if png is None:
            continue
        title = name.replace("margin_actuator_", "Torque-loop bandwidth and delay, ").replace(
            "margin_trunk_", "Trunk mass and inertia, ")
        out += [f"### {title}", "", f"![{title}](figures/{os.path.basename(png)})", "",
                *margin_table(out_dir, name, kind)]
    out.append(END)
    return "\n".join(out) + "\n"


def terrain_rows(out_dir, name):
    """Per recovery setting: the set's figures over its runs (sweep.csv and each case's summary.json)."""
    import csv
    path = os.path.join(out_dir, name, "sweep.csv")
    if not os.path.exists(path):
        return []
    rows = []
    with open(path) as f:
        cases = list(csv.DictReader(f))

    def num(v):
        return float(v) if v not in ("", None) else None

    for recovery in ("on", "off"):
        runs = [c for c in cases if c["recovery"] == recovery and c["status"] == "ok"]
        if not runs:
            continue
        after = [num(c["after_detection_max_ms"]) for c in runs if num(c["after_detection_max_ms"]) is not None]
        latency = [num(c["latency_max_ms"]) for c in runs if num(c["latency_max_ms"]) is not None]
        errors, slipped, estimated, normal, cone, odo = [], 0, 0, [], [], []
        for c in runs:
            summary = os.path.join(out_dir, name, "cases", c["id"], "summary.json")
            with open(summary) as f:
                s = json.load(f)
            errors += [p["max_error_pct"] for p in s["mu_estimate_error_pct"]["per_patch"]]
            slipped += sum(s["mu_estimate_coverage"]["slipped"])
            estimated += sum(s["mu_estimate_coverage"]["estimated"])
            for key, out in (("normal_error_max_deg", normal), ("normal_in_use_error_max_deg", cone),
                             ("odometry_per_50cm_cm", odo)):
                if num(c[key]) is not None:
                    out.append(num(c[key]))
        within10 = sum(e <= 10.0 for e in errors)
        rows.append(
            f"| {name.replace('terrain_', '')} | {recovery} | {len(runs)} | {sum(c['fell'] == 'True' for c in runs)} "
            f"| {sum(c['success'] == 'True' for c in runs)} | {fmt(max(after) if after else None)} "
            f"| {sum(a > 40.0 for a in after)} | {sum(int(c['missed_over_5mm'] or 0) for c in runs)} "
            f"| {fmt(max(latency) if latency else None)} "
            f"| {len(errors)}: {fmt(100.0 * within10 / len(errors) if errors else None)} % within 10 %, max "
            f"{fmt(max(errors) if errors else None, 1)} % | {estimated}/{slipped} "
            f"| {fmt(max(normal) if normal else None, 1)} / {fmt(max(cone) if cone else None, 1)} "
            f"| {fmt(max(odo) if odo else None, 2)} |")
    return rows


def terrain_section(out_dir):
    head = ("| set | recovery | runs | falls | got through | after det. max ms | runs over 40 ms "
            "| missed slips over 5 mm | latency max ms | mu estimates | (leg, patch) pairs estimated "
            "| normal error max deg: estimate / cone | odometry max cm per 50 cm |")
    rows = [head, "|" + "---|" * 13]
    missing = []
    for name in TERRAIN_SETS:
        got = terrain_rows(out_dir, name)
        rows += got
        if not got:
            missing.append(f"`{name}`")
    if missing:
        rows += ["", "Not run for this page: " + ", ".join(missing) + "."]
    return "\n".join([
        TERRAIN_BEGIN, "",
        "## Drawn terrains",
        "",
        "Terrains nobody tuned for (docs/scenarios.md, \"Drawn terrains\"): the validation set",
        "(`terrain.generate.seed` 1-256) and the test set (1000001-1000256), on the hyq plant, ODE",
        "(`validation`, `test`) and the first 64 of each on MuJoCo (`*_mujoco`), recovery on and off.",
        "A run gets through when it walks 2.5 m along its start heading. The test set is run only to",
        "report. Made by `python3 docs/real_plant.py --terrain` (`hyq_sim sweep",
        "sim_host/sweeps/terrain_<set>.yaml`).",
        "",
        *rows, "", TERRAIN_END]) + "\n"


def write_block(output, text, begin, end):
    old = open(output).read() if os.path.exists(output) else ""
    if begin in old and end in old:
        head, rest = old.split(begin, 1)
        tail = rest.split(end, 1)[1].lstrip("\n")
        new = head + text + tail
    else:
        new = old.rstrip("\n") + "\n\n" + text
    with open(output, "w") as f:
        f.write(new)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", action="store_true")
    ap.add_argument("--terrain", action="store_true")
    ap.add_argument("--wide", action="store_true")
    ap.add_argument("--fresh", action="store_true")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--sim", default=os.path.join(ROOT, "build", "host", "hyq_sim"))
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "out", "real_plant"))
    ap.add_argument("--output", default=os.path.join(ROOT, "docs", "results.md"))
    args = ap.parse_args()
    if args.run:
        for name in MARGIN:
            run_sweep(args.sim, os.path.join(ROOT, "sim_host", "sweeps", name + ".yaml"),
                      os.path.join(args.out_dir, name), args.jobs, args.fresh)
        for engine, seeds in (("ode", ODE_SEEDS), ("mujoco", MUJOCO_SEEDS)):
            for scenario, goal in SCENARIOS:
                run_sweep(args.sim, sweep_file(args.out_dir, scenario, goal, engine, seeds),
                          os.path.join(args.out_dir, f"{scenario}_{engine}"), args.jobs, args.fresh)
    if args.wide:
        for engine in ("ode", "mujoco"):
            for scenario, goal in SCENARIOS:
                run_sweep(args.sim, sweep_file(args.out_dir, scenario, goal, engine, WIDE_SEEDS, "hyq", "_wide"),
                          os.path.join(args.out_dir, f"{scenario}_{engine}_wide"), args.jobs, args.fresh)
    if args.terrain:
        for name in TERRAIN_SETS:
            run_sweep(args.sim, os.path.join(ROOT, "sim_host", "sweeps", name + ".yaml"),
                      os.path.join(args.out_dir, name), args.jobs, args.fresh)
        write_block(args.output, terrain_section(args.out_dir), TERRAIN_BEGIN, TERRAIN_END)
        print(f"wrote the drawn terrains' section of {os.path.relpath(args.output, ROOT)}")
    if args.run or args.wide or not args.terrain:
        write_block(args.output, section(args.out_dir, os.path.join(os.path.dirname(args.output), "figures")),
                    BEGIN, END)
        print(f"wrote the real-plant section of {os.path.relpath(args.output, ROOT)}")


if __name__ == "__main__":
    sys.exit(main())
