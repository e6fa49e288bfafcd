#!/usr/bin/env python3
"""Friction estimates of the front and the hind feet on the ice slab's two
iciest patches, per plant configuration: design-notes.md, "What the hyq
plant does to the friction estimates".

    build/host/hyq_sim sweep sim_host/sweeps/plant_parts_ice_patches.yaml \
        --jobs 2 --out out/notes/plant_parts
    python3 docs/plant_parts.py out/notes/plant_parts

For each parameter combination of the sweep (its `set` values, one row),
over its runs: the (run, leg, patch) pairs with a friction estimate on the
patches of mu <= ICE_MU, front feet and hind feet apart, with the median
and the largest of their worst errors (summary.json's
mu_estimate_error_pct.per_patch), and the worst error on any patch.
"""
import csv
import json
import os
import statistics
import sys

ICE_MU = 0.2   # [-] patches at or below this mu count
FRONT = (0, 1)  # LF, RF


def spread(errors):
    if not errors:
        return "-"
    return "%.1f / %.1f" % (statistics.median(errors), max(errors))


def main(folder):
    with open(os.path.join(folder, "cases.csv")) as f:
        cases = list(csv.DictReader(f))
    fixed = {"id", "point", "engine", "recovery", "seed"}
    groups = {}
    for case in cases:
        key = " ".join("%s=%s" % (k, v) for k, v in case.items() if k not in fixed)
        with open(os.path.join(folder, "cases", case["id"], "summary.json")) as f:
            summary = json.load(f)
        g = groups.setdefault(key, {"runs": 0, "front": [], "hind": [], "worst": []})
        g["runs"] += 1
        errors = summary["mu_estimate_error_pct"]
        if errors.get("max") is not None:
            g["worst"].append(errors["max"])
        for patch in errors.get("per_patch", []):
            if patch["mu_true"] > ICE_MU + 1e-9:
                continue
            g["front" if patch["leg"] in FRONT else "hind"].append(patch["max_error_pct"])
    print("| configuration | runs | front pairs | front err med / max % | hind pairs "
          "| hind err med / max % | worst per run med / max % |")
    print("|---|---|---|---|---|---|---|")
    for key, g in groups.items():
        print("| %s | %d | %d | %s | %d | %s | %s |" % (
            key, g["runs"], len(g["front"]), spread(g["front"]), len(g["hind"]),
            spread(g["hind"]), spread(g["worst"])))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
