#!/usr/bin/env python3
"""Rewrites the board-timing section of docs/performance.md (between the
<!-- timing:begin --> and <!-- timing:end --> markers) from the figures the
timing tests write (build/host/timing/<trace>.json, `make timing`)."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
TRACES = ["ice_patches", "ice_patches_probe", "ramp", "two_feet_ice", "stance_slip", "ice_to_grip", "slope_down", "freeze", "trot_flat",
          "trot_ice_patches", "crawl_to_trot", "freeze_ideal_plant", "ice_to_grip_ideal_plant", "trot_flat_ideal_plant"]
BEGIN, END = "<!-- timing:begin -->", "<!-- timing:end -->"


def k(x):
    return f"{x / 1000:.1f}k"


def render(runs):
    names = [s["name"] for s in runs[0]["stages"]]
    out = []
    out.append("Per stage and per trace: median / p99 / max instructions of each tick.\n")
    header = "| stage | " + " | ".join(f"{r['trace']} ({r['ticks']} ticks)" for r in runs) + " |"
    out.append(header)
    out.append("|---" * (len(runs) + 1) + "|")
    for i, name in enumerate(names):
        cells = [f"{k(r['stages'][i]['median'])} / {k(r['stages'][i]['p99'])} / {k(r['stages'][i]['max'])}"
                 for r in runs]
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    cells = [f"**{k(r['step']['median'])} / {k(r['step']['p99'])} / {k(r['step']['max'])}**" for r in runs]
    out.append("| **whole step** | " + " | ".join(cells) + " |")
    out.append("")
    worst = max(runs, key=lambda r: r["step"]["max"])
    w = worst["worst_tick"]
    out.append(f"The worst tick of all: {worst['trace']} tick {w['index']}, "
               f"{worst['step']['max']:.0f} instructions:\n")
    out.append("| " + " | ".join(names) + " |")
    out.append("|---" * len(names) + "|")
    out.append("| " + " | ".join(f"{v:.0f}" for v in w["stages"]) + " |")
    out.append("")
    stack = max(r["stack_peak_bytes"] for r in runs)
    out.append(f"Deepest stack use over all traces (painted stack): {stack} bytes. "
               f"Resolution of every count: {runs[0]['instructions_per_count']:.0f} instructions.")
    return "\n".join(out) + "\n"


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "host")
    runs = []
    for name in TRACES:
        path = os.path.join(build, "timing", name + ".json")
        if not os.path.exists(path):
            sys.exit(f"{path} missing: run `make timing` first")
        with open(path) as f:
            runs.append(json.load(f))
    doc_path = os.path.join(HERE, "performance.md")
    with open(doc_path) as f:
        doc = f.read()
    if BEGIN not in doc or END not in doc:
        sys.exit(f"{doc_path}: markers {BEGIN} / {END} missing")
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(doc_path + ".tmp", "w") as f:
        f.write(head + BEGIN + "\n" + render(runs) + END + tail)
    os.replace(doc_path + ".tmp", doc_path)
    print(f"{doc_path}: board timing table from {len(runs)} traces")


if __name__ == "__main__":
    main()
