#!/usr/bin/env python3
"""Runs the scenarios over seeds and writes docs/results.md from the runs.

    make results                              # = python3 docs/results.py --fresh (ODE seeds
                                              #   1-32, MuJoCo and stiffness seeds 1-8),
                                              #   1,152 runs, 10 min 16 s on 2 cores
    python3 docs/results.py [--seeds A-B] [--mujoco-seeds A-B] [--stiffness-seeds A-B]
                            [--jobs N] [--fresh] [--sim PATH] [--out-dir DIR] [--output FILE]

Runs, through `hyq_sim sweep` (docs/sweeps.md; one sweep per scenario and
recovery setting, out/results/<scenario>_<on|off>/, its cases in
cases/<engine>_<on|off>_s<seed>/), on ODE (the default engine) over --seeds
(default 1-32)

  - the slip scenarios (flat, ice_patches, ramp, stance_slip, two_feet_ice,
    ice_to_grip, ice_010, ramp_035; trot_ice_patches, trot_ramp,
    trot_push_ice and trot_ice_fast at a trot; crawl_to_trot, the gait
    switch), recovery on and off;
  - the locomotion scenarios ramp_grip (recovery off, as its file says),
    push, flat_hostile_sensors, trot_flat and trot_push (recovery on);
    flat's locomotion row is its recovery-on run;

then, over --mujoco-seeds (default 1-8),

  - the slip scenarios, recovery on and off, again on MuJoCo into
    out/results/mujoco/<scenario>_<on|off>/ (and the ODE runs
    of those seeds, if --seeds lacks them, for the side-by-side table);

and over --stiffness-seeds (default: the --mujoco-seeds),

  - ice_patches and ramp, recovery on, at each contact stiffness of
    STIFFNESS (MuJoCo physics.mujoco.timeconst, ODE
    physics.ode.stiffness_scale): a copy of the scenario file with its
    `name:` changed and a `physics:` section in place of any it had, written
    to out/results/stiffness/<scenario>_<engine>_<key>_<value>.yaml, run
    into out/results/stiffness/<that name>_on/;

at most --jobs sweeps at once, each one case at a time (default: the number
of processors). A case whose summary.json already exists is not run again
unless --fresh. Then it
reads every summary.json (docs/metrics.md defines the fields) and writes
--output (default docs/results.md). Standard library only.

    python3 docs/results.py --sweep FILE.yaml [FILE.yaml ...] [--recovery on|off]
                            [--seeds A-B] [--jobs N] [--sim PATH] --out-dir DIR

runs each scenario file (any YAML, e.g. a copy with one key changed) over the
seeds into DIR/<file>_<on|off>/ and prints one table row per file:
the figures docs/design-notes.md quotes.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SLIP_SCENARIOS = ["flat", "ice_patches", "ramp", "stance_slip", "two_feet_ice", "ice_to_grip", "ice_010",
                  "ramp_035", "trot_ice_patches", "trot_ramp", "crawl_to_trot", "trot_push_ice", "trot_ice_fast"]
# (scenario, recovery) of the locomotion table; flat's run is shared with the slip table.
LOCOMOTION = [("flat", "on"), ("ramp_grip", "off"), ("push", "on"), ("flat_hostile_sensors", "on"),
              ("trot_flat", "on"), ("trot_push", "on")]

# Where a run has "got through": the hind feet (0.37 m behind the base) past
# this x [m] at the end, without a fall. The base starts at x = 0, so this is
# distance_m - 0.37 > goal.
GOALS = {
    "ice_patches": (3.4, "past the last patch"),
    "ice_010": (3.4, "past the last patch"),
    "trot_ice_patches": (3.4, "past the last patch"),
    "trot_ice_fast": (6.0, "past the last patch"),
    "crawl_to_trot": (4.0, "past the last patch"),
    "trot_ramp": (3.0, "on the top"),
    "ramp": (3.0, "on the top"),
    "ramp_035": (3.0, "on the top"),
    "ramp_grip": (3.0, "on the top"),
    "ice_to_grip": (1.2, "off the ice"),
}
HIND_FEET_BEHIND_BASE = 0.37

# The contact stiffness settings: (engine, key under physics.<engine>, value,
# the engine's default?). MuJoCo's timeconst is solref's time constant [s]
# (larger: softer); ODE's stiffness_scale multiplies the contact's stiffness.
STIFFNESS_SCENARIOS = ["ice_patches", "ramp"]
STIFFNESS = [
    ("mujoco", "timeconst", 0.004, False),
    ("mujoco", "timeconst", 0.005, True),
    ("mujoco", "timeconst", 0.01, False),
    ("mujoco", "timeconst", 0.02, False),
    ("ode", "stiffness_scale", 0.3, False),
    ("ode", "stiffness_scale", 1, True),
    ("ode", "stiffness_scale", 3, False),
]

# --------------------------------------------------------------------------
# Hand-written text. It survives regeneration; the numbers in braces are
# filled in from the runs.

INTRO = """\
Every figure here comes from `hyq_sim` runs with sensor noise on
(docs/scenarios.md), one ODE step per 1 ms tick, on the ideal plant
(`--plant ideal`: the exact joint torques, no delays, the controller's own
bodies) except in the sections "On the real plant", "The margin map" and
"Drawn terrains", which run the hyq plant, the simulator's default, over seeds {seeds}
(`--seed N` draws another set of sensor noise and biases; each run is
reproducible bit for bit); the last two sections, on MuJoCo and over the
contact stiffness, run the seeds their headings name. One run of one case,
by hand:

```sh
make host
build/host/hyq_sim run sim_host/scenarios/<name>.yaml --plant ideal --recovery on|off --seed N --out out/<name>_<on|off>
make plots RUN=out/<name>_on      # figures 5-8 of the paper from that run
```

The walk on ice is chaotic: another seed can fall where seed 1 did not, and
any change to the controller re-deals which seeds fall. One seed is one
sample; the tables give, for each figure, the **median** over the runs and
the **worst** run (a robot that must not fall is judged by its worst case).
Metric definitions: docs/metrics.md. `tests/scenario/` asserts the main
outcomes on seeds 1-8 (ice_patches with recovery: seeds 1-16).
Measured findings behind the design choices: docs/design-notes.md.
"""

FIGURES = """\
## The paper's figures, from seed 1

`make run` draws them from logged seed-1 runs of ice_patches (recovery on,
and off for figure 6); `make plots RUN=out/<name>_on` from any run.

Friction estimates per leg on the ice patches, with the true mu under each
foot and the mu the QP uses ({fig5}):
![fig 5](figures/ice_patches_fig5_mu.png)

With the friction probe and the friction map on (`ice_patches_map.yaml`,
seed 1): Fig. 5 with each probe's answer starred, and the map the
controller built, cell by cell over the true friction (each cell's estimate,
the true mu under the feet that wrote it in brackets, its count of
estimates); `summary.json`'s `friction_map` has the same per cell
(docs/metrics.md). On the hyq plant (ODE): 40 probes, 10 answers, every one
within 4.3 % of the ground under its foot; 12 cells, 11 within 10 %, the
worst 10.2 % off.
`build/host/hyq_sim run sim_host/scenarios/ice_patches_map.yaml`,
then `make plots RUN=out/ice_patches_map`:
![fig 5 with the probe](figures/ice_patches_map_fig5_mu.png)
![friction map](figures/ice_patches_map_friction_map.png)

Odometry error without recovery (top: {odo_off}) and with it (bottom:
{odo_on}); each step of the upper curve is a slip that stayed in the
baseline's odometry:
![fig 6](figures/ice_patches_fig6_odometry.png)

The normal in use, its estimate and the truth during one slip; the friction
cone violation and a stance knee torque (ice patches, and the ramp):
![fig 7](figures/ice_patches_fig7_normal.png)
![fig 7 ramp](figures/ramp_fig7_normal.png)

Foot velocity norms along the ground and the slip flags around a slip (ice
patches, stance slip):
![fig 8](figures/ice_patches_fig8_slip_flags.png)
![fig 8 stance](figures/stance_slip_fig8_slip_flags.png)
"""

PAPER_NOTE = """\
The paper (Focchi et al., Sec. 5) shows one run per scenario; its numbers
are in the second column. "Goal" is this project's bar for every run.
Without recovery the paper's robot fell on the ice after a few steps; this
simulator's baseline does not fall there (it slides, loses ground and its
odometry drifts): docs/design-notes.md, "The baseline does not fall on the
ice patches".
"""

MUJOCO_TEXT = """\
The slip scenarios again on the second physics engine, MuJoCo
(`--engine mujoco`, its default contact: docs/scenarios.md, "Physics"). The
robot, terrain, sensor noise, controller and metrics are the ones of the ODE
runs; the contact is MuJoCo's soft constraint, integrated at the 1 ms tick.
One run by hand:

```sh
build/host/hyq_sim run sim_host/scenarios/<name>.yaml --plant ideal --recovery on|off --seed N --engine mujoco --out out/<name>_mujoco
```

With recovery on, {falls_on} of {runs_on} runs fall and {through_on} of
{goal_runs_on} runs of the scenarios with a goal get through; with it off,
{falls_off} of {runs_off} fall and {through_off} of {goal_runs_off} get
through. With recovery on there are {false_on} false detections in all runs,
the run's worst mu error is within 10 % in {mu_within_on} of the
{mu_runs_on} runs with an estimate (worst run {mu_worst_on} %), and the
odometry error per 50 cm is at most {odo_worst_on} cm. The columns are those
of the ODE tables above.
"""

COMPARE_TEXT = """\
Seeds {seeds} on both engines side by side; the ODE columns are the runs of
the ODE tables with these seeds. Over the {runs} runs per engine ({n_slip} slip
scenarios, recovery on and off): {falls_ode} falls on ODE and {falls_mj} on
MuJoCo; {fd_ode} and {fd_mj} false detections. With recovery on, the run's
worst mu error is within 10 % in {mu_ode} (ODE) and {mu_mj} (MuJoCo) of the
runs with an estimate. Distance: median over the runs; mu error: median /
worst run of the run's worst event; odometry: the worst run; false
detections: all runs together.
"""

STIFFNESS_TEXT = """\
ice_patches and ramp with recovery on, over seeds {seeds}, with the contact
softer or stiffer than each engine's default. Each setting is a copy of the
scenario file with its own name and a `physics:` section (docs/scenarios.md,
the key table), written to
out/results/stiffness/<scenario>_<engine>_<key>_<value>.yaml; one run by hand:
`build/host/hyq_sim run out/results/stiffness/<file>.yaml --recovery on --seed N --out DIR`.
Per setting: falls; the run's worst mu error, median / worst over the runs
with an estimate; the runs within 10 % of those with an estimate; the runs
with an estimate; the odometry error per 50 cm, median / worst run; the
false detections of all runs together; the run's longest slip after its
detection, median / worst run. On the softer contacts the longest of
those "slips" can be mostly the contact's elastic give: the foot moves
faster than the truth's 0.05 m/s while its force stays inside the cone,
and gives at most 20 ms apart count as one slip event (docs/metrics.md;
docs/design-notes.md, "What a soft contact hides from the estimator").
"""

STIFFNESS_MUJOCO_TEXT = """\
MuJoCo, `physics.mujoco.timeconst` (solref's time constant: a larger one is
a softer contact; default 0.005 s) from {lo} to {hi} s: {falls} falls in
{runs} runs. Across the settings the median of the runs' worst mu error lies
between {mu_med_lo} and {mu_med_hi} %, the worst run at {mu_worst} %;
{mu_within} of the {mu_runs} runs with an estimate are within 10 %. The
odometry error per 50 cm is at most {odo_worst} cm; {fd} false detections in
all.
"""

STIFFNESS_ODE_TEXT = """\
ODE, `physics.ode.stiffness_scale` (the contact's normal and tangential
stiffness times this; default 1; above 1 a tick takes at least
ceil(sqrt(scale)) ODE steps) from {lo} to {hi}: {falls} falls in {runs} runs. Across the settings
the median of the runs' worst mu error lies between {mu_med_lo} and
{mu_med_hi} %, the worst run at {mu_worst} %; {mu_within} of the {mu_runs}
runs with an estimate are within 10 %. The odometry error per 50 cm is at
most {odo_worst} cm; {fd} false detections in all.
"""

# --------------------------------------------------------------------------
# Running


def parse_seeds(text):
    if "-" in text:
        a, b = text.split("-", 1)
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def seeds_label(seeds):
    if seeds == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}-{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])
    return ", ".join(map(str, seeds))


def cases(args, seeds, mujoco_seeds, stiffness_seeds):
    """Every run of the page: (out_dir, scenario, recovery, seed, engine or None)."""
    out = []
    for seed in seeds:
        for s in SLIP_SCENARIOS:
            for rec in ("on", "off"):
                out.append((args.out_dir, s, rec, seed, None))
        for s, rec in LOCOMOTION:
            if s not in SLIP_SCENARIOS:
                out.append((args.out_dir, s, rec, seed, None))
    for seed in mujoco_seeds:
        for s in SLIP_SCENARIOS:
            for rec in ("on", "off"):
                if seed not in seeds:  # the ODE side of the side-by-side table
                    out.append((args.out_dir, s, rec, seed, None))
                out.append((mujoco_dir(args), s, rec, seed, "mujoco"))
    for seed in stiffness_seeds:
        for s in STIFFNESS_SCENARIOS:
            for setting in STIFFNESS:
                out.append((stiffness_dir(args), variant_file(args, s, setting), "on", seed, None))
    return out


def mujoco_dir(args):
    return os.path.join(args.out_dir, "mujoco")


def stiffness_dir(args):
    return os.path.join(args.out_dir, "stiffness")


def variant_file(args, scenario, setting):
    engine, key, value, _ = setting
    return os.path.join(stiffness_dir(args), f"{scenario}_{engine}_{key}_{value:g}.yaml")


def write_variants(args):
    """The stiffness settings' scenario files: each scenario file with its name
    changed and its `physics:` section (if any) replaced by the setting's."""
    os.makedirs(stiffness_dir(args), exist_ok=True)
    for s in STIFFNESS_SCENARIOS:
        with open(scenario_file(s)) as f:
            lines = f.read().splitlines()
        for setting in STIFFNESS:
            engine, key, value, _ = setting
            path = variant_file(args, s, setting)
            out, in_physics = [], False
            for line in lines:
                top_level = line[:1] not in ("", " ", "\t")
                if top_level:
                    in_physics = line.startswith("physics:")
                if in_physics:
                    continue
                out.append(f"name: {scenario_name(path)}" if line.startswith("name:") else line)
            out += ["# The ideal plant (docs/results.py):", "plant: {model: ideal}",
                    "# Contact stiffness setting (docs/results.py):",
                    f"physics: {{engine: {engine}, {engine}: {{{key}: {value:g}}}}}"]
            with open(path, "w") as f:
                f.write("\n".join(out) + "\n")


def scenario_file(scenario):
    return scenario if scenario.endswith(".yaml") else os.path.join(ROOT, "sim_host", "scenarios", scenario + ".yaml")


def scenario_name(scenario):
    name = os.path.basename(scenario)
    return name[:-len(".yaml")] if name.endswith(".yaml") else name


def case_engine(scenario, engine):
    """The engine a case runs on: the given one, else the scenario file's
    (`physics: {engine: ...}`, as the stiffness variants have), else ODE."""
    if engine:
        return engine
    with open(scenario_file(scenario)) as f:
        for line in f:
            if line.startswith("physics:") and "mujoco" in line.split("#")[0]:
                return "mujoco"
    return "ode"


def sweep_dir(out_dir, scenario, rec):
    return os.path.join(out_dir, f"{scenario_name(scenario)}_{rec}")


def case_dir(out_dir, scenario, rec, seed, engine=None):
    """Where `hyq_sim sweep` puts the case (docs/sweeps.md)."""
    return os.path.join(sweep_dir(out_dir, scenario, rec), "cases",
                        f"p000_{case_engine(scenario, engine)}_{rec}_s{seed}")


def plant_of(scenario):
    """The plant a case runs: the file's own `plant.model`, or the ideal
    plant where it names none (this page's tables are the ideal plant's; the
    hyq plant's are docs/real_plant.py's)."""
    with open(scenario_file(scenario)) as f:
        doc = yaml.safe_load(f) or {}
    plant = doc.get("plant") if isinstance(doc, dict) else None
    model = plant.get("model") if isinstance(plant, dict) else None
    return str(model) if model else "ideal"


def run_sweep(sim, out_dir, scenario, rec, engine, seeds, fresh):
    """One scenario, one recovery setting, one engine over the seeds: a sweep
    file beside its folder, run by `hyq_sim sweep` (one case at a time: the
    sweeps themselves run in parallel)."""
    folder = sweep_dir(out_dir, scenario, rec)
    os.makedirs(folder, exist_ok=True)
    sweep_file = folder + ".sweep.yaml"
    report = os.path.join(folder, "sweep.json")
    if os.path.exists(report):
        os.remove(report)  # a report left by an earlier start must not stand for this one
    with open(sweep_file, "w") as f:
        f.write(f"name: {os.path.basename(folder)}\n"
                f"scenario: {json.dumps(os.path.abspath(scenario_file(scenario)))}\n"
                f"seeds: [{', '.join(str(x) for x in sorted(seeds))}]\n"
                f"recovery: [{rec}]\n"
                f"engines: [{engine}]\n"
                f"set:\n  plant.model: [{plant_of(scenario)}]\n")
    cmd = [sim, "sweep", sweep_file, "--out", folder, "--jobs", "1", "--quiet", "--no-plots"]
    if fresh:
        cmd.append("--fresh")
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode == 0:
        return len(seeds), None
    bad = []
    if p.returncode == 1 and os.path.exists(report):
        with open(report) as f:
            bad = [c for g in json.load(f)["groups"] for c in g["not_completed"]]
    if bad:
        return len(seeds), "\n".join(f"{os.path.basename(folder)} {c['id']}: {c['status']} (exit {c['exit_code']}) "
                                     f"{c['error']}" for c in bad)
    return len(seeds), f"{os.path.basename(folder)}: hyq_sim sweep exit {p.returncode}\n{p.stdout}"


def run_all(args, all_cases):
    """Every case through `hyq_sim sweep`, one sweep per (folder, scenario,
    recovery, engine); a case already done is kept unless --fresh."""
    groups = {}
    for out_dir, scenario, rec, seed, engine in all_cases:
        if not args.fresh and os.path.exists(os.path.join(case_dir(out_dir, scenario, rec, seed, engine),
                                                          "summary.json")):
            continue
        groups.setdefault((out_dir, scenario, rec, case_engine(scenario, engine)), set()).add(seed)
    if not groups:
        return
    if not os.access(args.sim, os.X_OK):
        sys.exit(f"{args.sim} not found: run `make host` first")
    total = sum(len(v) for v in groups.values())
    print(f"running {total} cases in {len(groups)} sweeps, {args.jobs} at once", flush=True)
    t0 = time.monotonic()
    done = 0
    errors = []
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_sweep, args.sim, *k, seeds, args.fresh) for k, seeds in groups.items()]
        for f in futures:
            n, err = f.result()
            done += n
            if err:
                errors.append(err)
                print(err, file=sys.stderr, flush=True)
            print(f"  {done}/{total} ({time.monotonic() - t0:.0f} s)", flush=True)
    if errors:
        sys.exit(f"{len(errors)} sweeps had cases that did not run to their end")


# --------------------------------------------------------------------------
# Reading


def load(out_dir, scenario, rec, seeds, engine="ode"):
    runs = []
    for seed in seeds:
        path = os.path.join(case_dir(out_dir, scenario, rec, seed, engine), "summary.json")
        with open(path) as f:
            runs.append(json.load(f))
        if engine and runs[-1].get("engine", "ode") != engine:
            sys.exit(f"{path}: a run on {runs[-1]['engine']}, not {engine}: run with --fresh")
    return runs


def mu_samples(r):
    return sum(p["samples"] for p in r["mu_estimate_error_pct"]["per_patch"])


def odo_per_50cm_cm(r):
    walked = r["distance_walked_m"]
    return 100.0 * r["odometry_error_m"]["max"] * 0.5 / walked if walked > 0 else None


def reached(scenario, r):
    goal = GOALS.get(scenario)
    return goal is not None and not r["fell"] and r["distance_m"] - HIND_FEET_BEHIND_BASE > goal[0]


def vals(runs, get):
    out = []
    for r in runs:
        v = get(r)
        if v is not None:
            out.append(v)
    return out


def fmt(x, digits=1):
    """x with `digits` decimals; a count (digits 0) keeps .5 if it is a median between two."""
    if x is None:
        return "-"
    if digits == 0 and float(x) != int(x):
        digits = 1
    return f"{float(x):.{digits}f}"


def med_worst(xs, digits=1, worst=max):
    """'median / worst' over the runs that have the figure, '-' if none."""
    if not xs:
        return "-"
    return f"{fmt(statistics.median(xs), digits)} / {fmt(worst(xs), digits)}"


def seed_list(seeds):
    if not seeds:
        return ""
    parts, start, prev = [], seeds[0], seeds[0]
    for s in seeds[1:] + [None]:
        if s is not None and s == prev + 1:
            prev = s
            continue
        parts.append(f"{start}-{prev}" if prev > start + 1 else
                     (f"{start}, {prev}" if prev == start + 1 else str(start)))
        if s is not None:
            start = prev = s
    return ", ".join(parts)


def falls_cell(runs):
    fell = [r["seed"] for r in runs if r["fell"]]
    n = f"{len(fell)}/{len(runs)}"
    if not fell:
        return n
    times = [r["fall_time_s"] for r in runs if r["fell"]]
    return f"**{n}** (seeds {seed_list(fell)}; at {min(times):.0f}-{max(times):.0f} s)"


def reached_cell(scenario, runs):
    if scenario not in GOALS:
        return "-"
    return f"{sum(reached(scenario, r) for r in runs)}/{len(runs)}"


# --------------------------------------------------------------------------
# Tables


def row(cells):
    return "| " + " | ".join(cells) + " |"


def header(cells):
    return [row(cells), row(["---"] * len(cells))]


def outcome_table(data):
    lines = header(["scenario", "recovery", "falls", "got through", "distance [m]",
                    "slip events", "false detections", "freezes", "stance torque step [N m]"])
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            runs = data[(s, rec)]
            lines.append(row([
                s, rec, falls_cell(runs), reached_cell(s, runs),
                med_worst(vals(runs, lambda r: r["distance_m"]), 2, worst=min),
                med_worst(vals(runs, lambda r: r["slip_events"]), 0),
                med_worst(vals(runs, lambda r: r["false_detections"]), 0),
                med_worst(vals(runs, lambda r: r["freeze_events"]), 0),
                med_worst(vals(runs, lambda r: r["max_stance_torque_step_nm"]), 1),
            ]))
    return lines


def detection_table(data):
    lines = header(["scenario", "recovery", "missed slips", "missed slip's travel [mm], run's max",
                    "latency [ms], run's median",
                    "latency [ms], run's max", "slip after detection [ms], run's median",
                    "slip after detection [ms], run's max", "runs with median <= 40 ms"])
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            runs = data[(s, rec)]
            after = vals(runs, lambda r: r["slip_duration_after_detection_ms"]["median"])
            lines.append(row([
                s, rec,
                med_worst(vals(runs, lambda r: r["missed_slips"]), 0),
                med_worst(vals(runs, lambda r: r["missed_slip_distance_mm"]["max"])),
                med_worst(vals(runs, lambda r: r["detection_latency_ms"]["median"])),
                med_worst(vals(runs, lambda r: r["detection_latency_ms"]["max"]), 0),
                med_worst(after),
                med_worst(vals(runs, lambda r: r["slip_duration_after_detection_ms"]["max"]), 0),
                f"{sum(a <= 40.0 for a in after)}/{len(after)}" if after else "-",
            ]))
    return lines


def class_table(data):
    """Recovery on: the worst case of each run, touch-down and stance slips apart, and the
    slips with more than 5 mm of travel (docs/metrics.md, slip_classes, recall_by_travel)."""
    lines = header(["scenario", "touch-down slips: events / missed, all runs",
                    "touch-down: latency [ms], run's max", "touch-down: slip after detection [ms], run's max",
                    "stance slips: events / missed, all runs", "stance: latency [ms], run's max",
                    "stance: slip after detection [ms], run's max",
                    "slips over 5 mm: events / detected, all runs", "over 5 mm: latency [ms], run's max"])

    for sc in SLIP_SCENARIOS:
        runs = [r for r in data[(sc, "on")] if "slip_classes" in r]
        if not runs:
            continue
        cells = [sc]
        for c in ("touchdown", "stance"):
            k = [r["slip_classes"][c] for r in runs]
            cells += [f"{sum(x['events'] for x in k)} / {sum(x['missed'] for x in k)}",
                      med_worst(vals(k, lambda x: x["detection_latency_ms"]["max"]), 0),
                      med_worst(vals(k, lambda x: x["slip_duration_after_detection_ms"]["max"]), 0)]
        over5 = [r["recall_by_travel"][0] for r in runs]
        cells += [f"{sum(x['events'] for x in over5)} / {sum(x['detected'] for x in over5)}",
                  med_worst(vals(over5, lambda x: x["detection_latency_ms"]["max"]), 0)]
        lines.append(row(cells))
    return lines


def normal_in_use_max(r):
    return r.get("normal_in_use_error_deg", {}).get("max")


def coverage_cell(runs, legs):
    """Estimated / slipped (leg, patch) pairs of `legs`, all runs together."""
    slipped = estimated = 0
    for r in runs:
        c = r.get("mu_estimate_coverage")
        if c is None:
            return "-"
        slipped += sum(c["slipped"][i] for i in legs)
        estimated += sum(c["estimated"][i] for i in legs)
    return f"{estimated}/{slipped}" if slipped else "-"


def estimate_table(data):
    lines = header(["scenario", "recovery", "mu error [%], run's max",
                    "runs within 10 % (of runs with an estimate)", "mu samples, all runs",
                    "patches estimated, front feet", "patches estimated, hind feet",
                    "normal error [deg], run's max", "normal in use error [deg], run's max",
                    "odometry error per 50 cm [cm]", "odometry error max [cm]"])
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            runs = data[(s, rec)]
            mu = vals(runs, lambda r: r["mu_estimate_error_pct"]["max"])
            lines.append(row([
                s, rec, med_worst(mu),
                f"{sum(m <= 10.0 for m in mu)}/{len(mu)}" if mu else "-",
                str(sum(mu_samples(r) for r in runs)),
                coverage_cell(runs, (0, 1)), coverage_cell(runs, (2, 3)),
                med_worst(vals(runs, lambda r: r["normal_error_deg"]["max"])),
                med_worst(vals(runs, normal_in_use_max)),
                med_worst(vals(runs, odo_per_50cm_cm), 2),
                med_worst(vals(runs, lambda r: 100.0 * r["odometry_error_m"]["max"]), 1),
            ]))
    return lines


def seed1_table(data, seed):
    lines = header(["scenario", "recovery", "fell", "distance [m]", "slip events", "missed",
                    "false det.", "latency median / max [ms]", "slip after detection median / max [ms]",
                    "freezes", "mu error max [%] (samples)", "normal error max [deg]",
                    "normal in use error max [deg]", "odometry error max [cm]",
                    "stance torque step max [N m]"])
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            r = next(r for r in data[(s, rec)] if r["seed"] == seed)
            lat, aft = r["detection_latency_ms"], r["slip_duration_after_detection_ms"]
            mu = r["mu_estimate_error_pct"]["max"]
            lines.append(row([
                s, rec, f"**yes, {r['fall_time_s']:.1f} s**" if r["fell"] else "no",
                fmt(r["distance_m"], 2), str(r["slip_events"]), str(r["missed_slips"]),
                str(r["false_detections"]),
                f"{fmt(lat['median'])} / {fmt(lat['max'], 0)}",
                f"{fmt(aft['median'])} / {fmt(aft['max'], 0)}",
                str(r["freeze_events"]),
                f"{fmt(mu)} ({mu_samples(r)})" if mu is not None else "-",
                fmt(r["normal_error_deg"]["max"]),
                fmt(normal_in_use_max(r)),
                fmt(100.0 * r["odometry_error_m"]["max"], 1),
                fmt(r["max_stance_torque_step_nm"], 1),
            ]))
    return lines


def locomotion_table(data):
    lines = header(["scenario", "recovery", "falls", "got through", "distance [m]",
                    "false detections", "freezes", "stance torque step [N m]", "odometry error max [cm]"])
    what = {"flat": "flat (mu 0.8, 60 s crawl)", "ramp_grip": "ramp_grip (0.25 rad, mu 0.8, 100 s)",
            "push": "push (standing, 150 N sideways for 0.2 s)",
            "flat_hostile_sensors": "flat_hostile_sensors (flat, every sensor bias at its specified worst, noise x3)",
            "trot_flat": "trot_flat (mu 0.8, a 0.5 m/s trot from standing, 60 s)",
            "trot_push": "trot_push (a 0.5 m/s trot, 150 N sideways for 0.2 s at 8 s, then the other way at 12.3 s)"}
    for s, rec in LOCOMOTION:
        runs = data[(s, rec)]
        lines.append(row([
            what[s], rec, falls_cell(runs), reached_cell(s, runs),
            med_worst(vals(runs, lambda r: r["distance_m"]), 2 if s != "push" else 3,
                      worst=min if s != "push" else max),
            med_worst(vals(runs, lambda r: r["false_detections"]), 0),
            med_worst(vals(runs, lambda r: r["freeze_events"]), 0),
            med_worst(vals(runs, lambda r: r["max_stance_torque_step_nm"]), 1),
            med_worst(vals(runs, lambda r: 100.0 * r["odometry_error_m"]["max"]), 1),
        ]))
    return lines


def slip_tables(data, estimate_intro=()):
    """The outcome, detection and estimate tables of a set of runs, with
    their headings; estimate_intro: lines above the estimate table."""
    return ["### Outcome", "", *outcome_table(data), "",
            "### Detection (slip events of stance feet, per run)", "", *detection_table(data), "",
            "### Worst cases by slip class, recovery on", "",
            "A touch-down slip starts within 0.2 s of its foot's touch-down, a stance slip later",
            "(docs/metrics.md); events and missed are summed over the runs, the latencies and durations",
            "are each run's maximum, median / worst run.", "", *class_table(data), "",
            "### Estimates and odometry", "", *estimate_intro, *estimate_table(data), ""]


def paper_table(data):
    def on(s):
        return data[(s, "on")]

    def off(s):
        return data[(s, "off")]

    def n_falls(runs):
        return f"{sum(r['fell'] for r in runs)}/{len(runs)} fall"

    def through(s, runs):
        return f"{sum(reached(s, r) for r in runs)}/{len(runs)} {GOALS[s][1]}"

    def mu_cell(runs):
        mu = vals(runs, lambda r: r["mu_estimate_error_pct"]["max"])
        return (f"run's worst event: median {statistics.median(mu):.1f} %, worst run {max(mu):.1f} %; "
                f"{sum(m <= 10.0 for m in mu)}/{len(mu)} runs within 10 %")

    def odo_cell(runs):
        o = vals(runs, odo_per_50cm_cm)
        return f"median {statistics.median(o):.2f} cm, worst run {max(o):.2f} cm"

    def after_cell(runs):
        a = vals(runs, lambda r: r["slip_duration_after_detection_ms"]["median"])
        m = vals(runs, lambda r: r["slip_duration_after_detection_ms"]["max"])
        return (f"run's median: median {statistics.median(a):.1f} ms, worst run {max(a):.1f} ms "
                f"({sum(x <= 40.0 for x in a)}/{len(a)} runs <= 40 ms); longest single slip {max(m):.0f} ms")

    def latency_cell(runs):
        a = vals(runs, lambda r: r["detection_latency_ms"]["median"])
        return f"run's median: median {statistics.median(a):.1f} ms, worst run {max(a):.1f} ms"

    def torque_cell(runs):
        t = vals(runs, lambda r: r["max_stance_torque_step_nm"])
        return f"median {statistics.median(t):.1f} N m, worst run {max(t):.1f} N m"

    def dist(runs, worst=min):
        d = vals(runs, lambda r: r["distance_m"])
        return f"{statistics.median(d):.2f} m median, {worst(d):.2f} m {'shortest' if worst is min else 'longest'}"

    ip, ipo = on("ice_patches"), off("ice_patches")
    rows = [
        ("ice_patches on: crosses, no fall", "crosses all patches", "every run",
         f"{n_falls(ip)}; {through('ice_patches', ip)}; {dist(ip)}"),
        ("ice_patches off", "falls after a few steps", "-",
         f"{n_falls(ipo)}; {through('ice_patches', ipo)}; {dist(ipo, max)}"),
        ("ice_patches on: mu error", "< 13 %", "<= 10 %", mu_cell(ip)),
        ("ice_patches on: odometry error per 50 cm", "< 1 cm", "<= 1 cm", odo_cell(ip)),
        ("ice_patches off: odometry error per 50 cm", "18 cm", "-", odo_cell(ipo)),
        ("ramp on: climbs, no fall", "climbs", "every run",
         f"{n_falls(on('ramp'))}; {through('ramp', on('ramp'))}; off: {n_falls(off('ramp'))}"),
        ("ramp on: slip over after detection", "52 ms (one event)", "<= 40 ms", after_cell(on("ramp"))),
        ("ramp on: no torque step in stance legs", "none", "< 25 N m", torque_cell(on("ramp"))),
        ("stance_slip on: slip over after detection", "< 40 ms", "<= 40 ms", after_cell(on("stance_slip"))),
        ("stance_slip on: detection latency", "-", "<= 10 ms", latency_cell(on("stance_slip"))),
        ("two_feet_ice on: no fall", "-", "every run",
         f"{n_falls(on('two_feet_ice'))}; {dist(on('two_feet_ice'))}; off: {dist(off('two_feet_ice'), max)}"),
        ("ice_to_grip on: no fall", "-", "every run",
         f"{n_falls(on('ice_to_grip'))}; {dist(on('ice_to_grip'))}; off: {dist(off('ice_to_grip'), max)}"),
        ("ice_010 on (four patches of mu 0.10): crosses, no fall", "-", "every run",
         f"{n_falls(on('ice_010'))}; {through('ice_010', on('ice_010'))}; {dist(on('ice_010'))}; "
         f"off: {through('ice_010', off('ice_010'))}"),
        ("ramp_035 on (0.35 rad, mu 0.55): climbs, no fall", "-", "every run",
         f"{n_falls(on('ramp_035'))}; {through('ramp_035', on('ramp_035'))}; "
         f"off: {n_falls(off('ramp_035'))}, {through('ramp_035', off('ramp_035'))}"),
        ("flat on: false detections in 60 s", "-", "0",
         f"{sum(r['false_detections'] for r in on('flat'))} in {len(on('flat'))} runs"),
    ]
    lines = header(["item", "paper", "goal", "measured"])
    for r in rows:
        lines.append(row(list(r)))
    return lines


def figures_text(data, seed):
    ip = next(r for r in data[("ice_patches", "on")] if r["seed"] == seed)
    ipo = next(r for r in data[("ice_patches", "off")] if r["seed"] == seed)
    mu = ip["mu_estimate_error_pct"]
    legs = [n for n, v in zip(["LF", "RF", "LH", "RH"], mu["per_leg"]) if v is not None]
    fig5 = (f"seed {seed}: {mu_samples(ip)} sampled events, on {', '.join(legs) or 'no leg'}, the worst "
            f"{fmt(mu['max'])} % off; a leg whose slips all ended before an estimate existed runs at the "
            f"floor mu, 0.07, until a slip-free second on grip lets it rise" if mu["max"] is not None else
            f"seed {seed}: no sampled event")

    def odo(r):
        return (f"{100 * r['odometry_error_m']['max']:.1f} cm at most, the robot {r['distance_m']:.2f} m on "
                f"after {r['sim_time_s']:.0f} s" + (", fallen" if r["fell"] else ""))

    return FIGURES.format(fig5=fig5, odo_off=odo(ipo), odo_on=odo(ip))


def sweep_table(args, seeds):
    lines = header(["file", "recovery", "falls", "distance [m]", "slip events",
                    "latency [ms], run's median", "slip after detection [ms], run's median",
                    "mu error [%], run's max", "runs within 10 %", "mu samples",
                    "normal error [deg]", "normal in use error [deg]", "odometry per 50 cm [cm]",
                    "false detections",
                    "freezes, all runs", "stance torque step [N m]"])
    for f in args.sweep:
        runs = load(args.out_dir, f, args.recovery, seeds, engine=None)
        mu = vals(runs, lambda r: r["mu_estimate_error_pct"]["max"])
        lines.append(row([
            scenario_name(f), args.recovery, falls_cell(runs),
            med_worst(vals(runs, lambda r: r["distance_m"]), 2, worst=min),
            med_worst(vals(runs, lambda r: r["slip_events"]), 0),
            med_worst(vals(runs, lambda r: r["detection_latency_ms"]["median"])),
            med_worst(vals(runs, lambda r: r["slip_duration_after_detection_ms"]["median"])),
            med_worst(mu),
            f"{sum(m <= 10.0 for m in mu)}/{len(mu)}" if mu else "-",
            str(sum(mu_samples(r) for r in runs)),
            med_worst(vals(runs, lambda r: r["normal_error_deg"]["max"])),
            med_worst(vals(runs, normal_in_use_max)),
            med_worst(vals(runs, odo_per_50cm_cm), 2),
            med_worst(vals(runs, lambda r: r["false_detections"]), 0),
            str(sum(r["freeze_events"] for r in runs)),
            med_worst(vals(runs, lambda r: r["max_stance_torque_step_nm"]), 1),
        ]))
    return lines


def mu_worsts(runs):
    return vals(runs, lambda r: r["mu_estimate_error_pct"]["max"])


def within_10(mu):
    return sum(m <= 10.0 for m in mu)


def max_or_none(xs):
    return max(xs) if xs else None


def count_cell(n, total):
    return f"**{n}/{total}**" if n else f"0/{total}"


def mujoco_text(data, seeds):
    def all_runs(rec, goal_only=False):
        return [(s, r) for s in SLIP_SCENARIOS if not goal_only or s in GOALS for r in data[(s, rec)]]

    on = [r for _, r in all_runs("on")]
    mu = mu_worsts(on)
    f = {"seeds": seeds_label(seeds), "false_on": sum(r["false_detections"] for r in on),
         "mu_within_on": within_10(mu), "mu_runs_on": len(mu), "mu_worst_on": fmt(max_or_none(mu)),
         "odo_worst_on": fmt(max_or_none(vals(on, odo_per_50cm_cm)), 2)}
    for rec in ("on", "off"):
        runs = all_runs(rec)
        goal = all_runs(rec, goal_only=True)
        f.update({f"falls_{rec}": sum(r["fell"] for _, r in runs), f"runs_{rec}": len(runs),
                  f"through_{rec}": sum(reached(s, r) for s, r in goal), f"goal_runs_{rec}": len(goal)})
    return MUJOCO_TEXT.format(**f)


def compare_text(ode, mj, seeds):
    def figures(data):
        runs = [r for k in data for r in data[k]]
        mu = [m for s in SLIP_SCENARIOS for m in mu_worsts(data[(s, "on")])]
        return (len(runs), sum(r["fell"] for r in runs), sum(r["false_detections"] for r in runs),
                f"{within_10(mu)}/{len(mu)}")

    n, falls_ode, fd_ode, mu_ode = figures(ode)
    _, falls_mj, fd_mj, mu_mj = figures(mj)
    return COMPARE_TEXT.format(seeds=seeds_label(seeds), runs=n, n_slip=len(SLIP_SCENARIOS), falls_ode=falls_ode,
                               falls_mj=falls_mj,
                               fd_ode=fd_ode, fd_mj=fd_mj, mu_ode=mu_ode, mu_mj=mu_mj)


def compare_table(ode, mj):
    cols = ["falls", "distance [m], median", "false detections", "mu error [%], run's max",
            "runs within 10 %", "odometry per 50 cm [cm], worst"]
    lines = header(["scenario", "recovery"] + [f"{c}: {e}" for c in cols for e in ("ODE", "MuJoCo")])
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            cells = [s, rec]
            pair = (ode[(s, rec)], mj[(s, rec)])
            for runs in pair:
                cells.append(count_cell(sum(r["fell"] for r in runs), len(runs)))
            for runs in pair:
                d = vals(runs, lambda r: r["distance_m"])
                cells.append(fmt(statistics.median(d), 2) if d else "-")
            for runs in pair:
                cells.append(str(sum(r["false_detections"] for r in runs)))
            for runs in pair:
                cells.append(med_worst(mu_worsts(runs)))
            for runs in pair:
                mu = mu_worsts(runs)
                cells.append(f"{within_10(mu)}/{len(mu)}" if mu else "-")
            for runs in pair:
                cells.append(fmt(max_or_none(vals(runs, odo_per_50cm_cm)), 2))
            lines.append(row(cells))
    return lines


def setting_label(setting):
    engine, key, value, default = setting
    unit = " s" if key == "timeconst" else ""
    return f"{key} {value:g}{unit}" + (" (default)" if default else "")


def stiffness_table(data, engine):
    lines = header(["scenario", "setting", "falls", "mu error [%], run's max",
                    "runs within 10 % (of runs with an estimate)", "runs with an estimate",
                    "odometry error per 50 cm [cm]", "false detections, all runs",
                    "slip after detection [ms], run's max"])
    for s in STIFFNESS_SCENARIOS:
        for setting in STIFFNESS:
            if setting[0] != engine:
                continue
            runs = data[(s, setting)]
            mu = mu_worsts(runs)
            lines.append(row([
                s, setting_label(setting), falls_cell(runs), med_worst(mu),
                f"{within_10(mu)}/{len(mu)}" if mu else "-", f"{len(mu)}/{len(runs)}",
                med_worst(vals(runs, odo_per_50cm_cm), 2),
                str(sum(r["false_detections"] for r in runs)),
                med_worst(vals(runs, lambda r: r["slip_duration_after_detection_ms"]["max"]), 0),
            ]))
    return lines


def stiffness_text(data, engine):
    settings = [st for st in STIFFNESS if st[0] == engine]
    runs = [r for s in STIFFNESS_SCENARIOS for st in settings for r in data[(s, st)]]
    mu = mu_worsts(runs)
    medians = [statistics.median(m) for m in
               (mu_worsts(data[(s, st)]) for s in STIFFNESS_SCENARIOS for st in settings) if m]
    values = [st[2] for st in settings]
    text = STIFFNESS_MUJOCO_TEXT if engine == "mujoco" else STIFFNESS_ODE_TEXT
    return text.format(lo=f"{min(values):g}", hi=f"{max(values):g}", falls=sum(r["fell"] for r in runs),
                       runs=len(runs), mu_med_lo=fmt(min(medians) if medians else None),
                       mu_med_hi=fmt(max_or_none(medians)), mu_worst=fmt(max_or_none(mu)),
                       mu_within=within_10(mu), mu_runs=len(mu),
                       odo_worst=fmt(max_or_none(vals(runs, odo_per_50cm_cm)), 2),
                       fd=sum(r["false_detections"] for r in runs))


def write_results(args, seeds, mujoco_seeds, stiffness_seeds):
    data = {}
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            data[(s, rec)] = load(args.out_dir, s, rec, seeds)
    for s, rec in LOCOMOTION:
        if (s, rec) not in data:
            data[(s, rec)] = load(args.out_dir, s, rec, seeds)
    mj, ode_m, stiff = {}, {}, {}
    for s in SLIP_SCENARIOS:
        for rec in ("on", "off"):
            mj[(s, rec)] = load(mujoco_dir(args), s, rec, mujoco_seeds, engine="mujoco")
            ode_m[(s, rec)] = load(args.out_dir, s, rec, mujoco_seeds)
    for s in STIFFNESS_SCENARIOS:
        for st in STIFFNESS:
            stiff[(s, st)] = load(stiffness_dir(args), variant_file(args, s, st), "on", stiffness_seeds,
                                  engine=st[0])
    label = seeds_label(seeds)
    mlabel, slabel = seeds_label(mujoco_seeds), seeds_label(stiffness_seeds)
    seed1 = seeds[0]
    options = f"--seeds {label} --mujoco-seeds {mlabel}" + (
        f" --stiffness-seeds {slabel}" if slabel != mlabel else "")
    cmd = ("make results" if (label, mlabel, slabel) == ("1-32", "1-8", "1-8")
           else f"python3 docs/results.py {options}")
    out = [
        "# Results",
        "",
        f"<!-- Generated by `{cmd}` (docs/results.py) from the runs' summary.json under out/results/;",
        "     do not edit: change docs/results.py and regenerate. -->",
        "",
        (f"Generated by `make results` (`python3 docs/results.py --fresh {options}`),\n"
         "which builds the simulator, runs"
         if cmd == "make results" else f"Generated by `{cmd}`, which runs"),
        f"every case below (on ODE over seeds {label}; on MuJoCo over seeds {mlabel}; the contact",
        f"stiffness settings over seeds {slabel}) and writes this page.",
        "",
        INTRO.format(seeds=label),
        "## Against the paper",
        "",
        PAPER_NOTE,
        *paper_table(data),
        "",
        f"## Slip scenarios, seeds {label}: median / worst run",
        "",
        f"Each cell is the median over the {len(seeds)} runs of a case and, after the slash, the worst",
        "run (the largest figure; for the distance, the shortest). \"run's median\" and \"run's max\" are",
        "the run's own median and maximum over its slip events. Cases without the figure show -.",
        "A run that fell includes the fall in its torque step and odometry figures. \"Got through\": the",
        "hind feet (0.37 m behind the base) past the last patch, the ice or the slope at the end,",
        "without a fall.",
        "",
        *slip_tables(data, ["The mu error is each run's worst sampled slip event (docs/metrics.md); runs without a",
                            "sample are left out of the median and the worst. The normal error is the estimate's",
                            "(events without one give no sample); the normal in use is the cone's the QP used at the",
                            "event's end, estimated or not: on the ramps, the whole slope at the front feet's first",
                            "touch-down on it (docs/design-notes.md, \"The normal at a first touch-down on a new",
                            "slope\"). With recovery off every cone is about the plane through all feet, and a robot",
                            "that falls takes that plane with it. \"Patches estimated\": of the (leg, patch) pairs",
                            "on which a leg had a detected slip, those with a friction estimate, all runs together",
                            "(`mu_estimate_coverage`); a front foot's slips on ice are light touch-downs that give",
                            "none (docs/design-notes.md, \"Why a landing front foot gets no estimate\").", ""]),
        f"## Locomotion, seeds {label}",
        "",
        "The base controller on good ground; each scenario with its file's recovery setting",
        "(ramp_grip is the base controller's own test, with recovery off). For push the distance is",
        "the drift after the push; its worst is the largest.",
        "",
        *locomotion_table(data),
        "",
        f"## Seed {seed1}, the run the figures come from",
        "",
        *seed1_table(data, seed1),
        "",
        figures_text(data, seed1).rstrip(),
        "",
        f"## On MuJoCo, seeds {mlabel}",
        "",
        mujoco_text(mj, mujoco_seeds),
        *slip_tables(mj),
        f"### ODE vs MuJoCo, seeds {mlabel}",
        "",
        compare_text(ode_m, mj, mujoco_seeds),
        *compare_table(ode_m, mj),
        "",
        f"## Contact stiffness, seeds {slabel}",
        "",
        STIFFNESS_TEXT.format(seeds=slabel),
        "### MuJoCo: contact time constant",
        "",
        stiffness_text(stiff, "mujoco"),
        *stiffness_table(stiff, "mujoco"),
        "",
        "### ODE: contact stiffness scale",
        "",
        stiffness_text(stiff, "ode"),
        *stiffness_table(stiff, "ode"),
        "",
    ]
    text = "\n".join(out)
    # The real-plant and drawn-terrain sections (docs/real_plant.py, `make real-plant`) are kept as they are.
    if os.path.exists(args.output):
        old = open(args.output).read()
        for tag in ("real-plant", "terrain"):
            begin, end = f"<!-- {tag}:begin", f"<!-- {tag}:end -->"
            if begin in old and end in old:
                block = old[old.index(begin):old.index(end) + len(end)]
                text = text.rstrip("\n") + "\n\n" + block + "\n"
    with open(args.output, "w") as f:
        f.write(text)
    print(f"wrote {os.path.relpath(args.output, ROOT)} ({len(seeds)} seeds on ODE, {len(mujoco_seeds)} on "
          f"MuJoCo, {len(stiffness_seeds)} per stiffness setting)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="1-32", help="A-B or a comma list (default 1-32)")
    ap.add_argument("--mujoco-seeds", default="1-8",
                    help="seeds of the MuJoCo section and the side-by-side table (default 1-8)")
    ap.add_argument("--stiffness-seeds", help="seeds of the contact stiffness section (default: --mujoco-seeds)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="parallel runs (default nproc)")
    ap.add_argument("--fresh", action="store_true", help="run every case again")
    ap.add_argument("--sim", default=os.path.join(ROOT, "build", "host", "hyq_sim"), help="the hyq_sim binary")
    ap.add_argument("--out-dir", default=os.path.join(ROOT, "out", "results"))
    ap.add_argument("--output", default=os.path.join(ROOT, "docs", "results.md"))
    ap.add_argument("--sweep", nargs="+", metavar="FILE.yaml", help="run these files over the seeds, print a table")
    ap.add_argument("--recovery", choices=["on", "off"], default="on", help="with --sweep (default on)")
    args = ap.parse_args()
    seeds = parse_seeds(args.seeds)
    t0 = time.monotonic()
    if args.sweep:
        run_all(args, [(args.out_dir, f, args.recovery, seed, None) for f in args.sweep for seed in seeds])
        print("\n".join(sweep_table(args, seeds)))
    else:
        mujoco_seeds = parse_seeds(args.mujoco_seeds)
        stiffness_seeds = parse_seeds(args.stiffness_seeds or args.mujoco_seeds)
        write_variants(args)
        run_all(args, cases(args, seeds, mujoco_seeds, stiffness_seeds))
        write_results(args, seeds, mujoco_seeds, stiffness_seeds)
    print(f"done in {time.monotonic() - t0:.0f} s")


if __name__ == "__main__":
    main()
