#!/usr/bin/env bash
# Runs ssl-evaluate in its three modes and turns the CSVs into PNG plots:
#   fig4-similarity.png      running averages of the similarity measures (the paper's Figure 4)
#   fig5-confidence.png      running average confidence of the 1st and 2nd prediction (Figure 5)
#   error-vs-horizon.png     position error in mm against horizon in seconds: the model against
#                            persistence, constant velocity and damped constant velocity
#   accuracy-vs-horizon.png  exact cell and state against horizon in seconds, same methods
#   reliability.png          reliability diagrams of the per-robot probability and the formation
#                            confidence
#   reliability-by-grid.png  the same for every grid of the grid sweep, with each horizon's ECE
#   grid-sweep.png           accuracy, table memory and prediction time per grid
#
#   scripts/plot-eval.sh [OUTPUT_DIR]      (default: build/eval)
# Extra ssl-evaluate options can be given in SSLF_EVAL_OPTIONS, e.g. "--jitter-mm 20"; those for
# holdout and grid-sweep alone in SSLF_HOLDOUT_OPTIONS, e.g. to evaluate on the shared grSim
# recordings: SSLF_HOLDOUT_OPTIONS="--train-log A.log.gz --test-log B.log.gz --sampling frame
# --step 1".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

out="${1:-$SSLF_ROOT/build/eval}"
build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
SSLF_PACKAGES+=(python3 python3-matplotlib)
sslf_install_packages
sslf_build_quietly "$build_dir" || exit 1
mkdir -p "$out"
evaluate="$build_dir/predictor/ssl-evaluate"
# shellcheck disable=SC2086
"$evaluate" paper -o "$out" --overwrite ${SSLF_EVAL_OPTIONS:-} | tee "$out/paper.txt"
# shellcheck disable=SC2086
"$evaluate" holdout -o "$out" --overwrite ${SSLF_EVAL_OPTIONS:-} ${SSLF_HOLDOUT_OPTIONS:-} | tee "$out/holdout.txt"
# shellcheck disable=SC2086
"$evaluate" grid-sweep -o "$out" --overwrite ${SSLF_EVAL_OPTIONS:-} ${SSLF_HOLDOUT_OPTIONS:-} | tee "$out/grid-sweep.txt"

# Debian's python3 (where python3-matplotlib lives), whatever else is first on PATH.
MPLBACKEND=Agg /usr/bin/python3 - "$out" <<'PY'
import csv, sys, os
import matplotlib.pyplot as plt

out = sys.argv[1]
def rows(name):
    with open(os.path.join(out, name)) as f:
        return list(csv.DictReader(f))

paper = rows("paper-running-averages.csv")
tests = [int(r["test"]) for r in paper]
fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(tests, [float(r["count_per_formation"]) for r in paper], label="count (ours)")
ax.plot(tests, [float(r["distance_per_formation"]) for r in paper], label="distance (ours)")
ax.axhline(5.5608, color="C0", linestyle=":", label="count (paper, 5.5608)")
ax.axhline(7.3226, color="C1", linestyle=":", label="distance (paper, 7.3226)")
ax.set_xlabel("test"); ax.set_ylabel("average measure per formation")
ax.set_title("Average similarity measures (paper Figure 4)"); ax.legend()
fig.tight_layout(); fig.savefig(os.path.join(out, "fig4-similarity.png"), dpi=110)

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(tests, [float(r["confidence_1"]) for r in paper], label="1st predicted formation")
ax.plot(tests, [float(r["confidence_2"]) for r in paper], label="2nd predicted formation")
ax.set_xlabel("test"); ax.set_ylabel("average confidence")
ax.set_title("Confidence level decrease (paper Figure 5)"); ax.legend()
fig.tight_layout(); fig.savefig(os.path.join(out, "fig5-confidence.png"), dpi=110)

holdout = rows("holdout-accuracy.csv")
methods = ["model", "persistence", "constant velocity", "damped constant velocity"]
# The horizons in seconds are each a model of their own (horizon_steps 1); the chains of --step
# follow them in the file and are left out here, so each horizon appears once.
def one_step_rows(method):
    seen, out = set(), []
    for r in holdout:
        if r["method"] != method or r["horizon_steps"] != "1" or r["horizon_s"] in seen:
            continue
        seen.add(r["horizon_s"]); out.append(r)
    return sorted(out, key=lambda r: float(r["horizon_s"]))
fig, ax = plt.subplots(figsize=(7, 4.5))
for m in methods:
    points = [(float(r["horizon_s"]), float(r["mean_error_mm"])) for r in one_step_rows(m)
              if int(r["robots"]) > 0]
    ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=m)
ax.set_xlabel("horizon (s)"); ax.set_ylabel("mean position error (mm)")
ax.set_title("Held-out position error against horizon"); ax.legend()
fig.tight_layout(); fig.savefig(os.path.join(out, "error-vs-horizon.png"), dpi=110)

fig, axes = plt.subplots(1, 2, figsize=(11, 4))
for ax, key, label in zip(axes, ["cell_accuracy", "state_accuracy"], ["exact cell", "exact state"]):
    for m in methods:
        points = [(float(r["horizon_s"]), float(r[key])) for r in one_step_rows(m)
                  if int(r["robots"]) > 0]
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=m)
    ax.set_xlabel("horizon (s)"); ax.set_title(label)
axes[0].legend()
fig.suptitle("Held-out accuracy in cells: model against baselines")
fig.tight_layout(); fig.savefig(os.path.join(out, "accuracy-vs-horizon.png"), dpi=110)

reliability = rows("holdout-reliability.csv")
fig, axes = plt.subplots(1, 2, figsize=(10, 5))
for ax, quantity in zip(axes, ["robot", "formation"]):
    ax.plot([0, 1], [0, 1], color="grey", linestyle=":", label="perfect calibration")
    done = set()
    for r0 in reliability:
        key = (r0["horizon_steps"], r0["horizon_s"])
        if r0["quantity"] != quantity or r0["horizon_steps"] != "1" or key in done:
            continue
        done.add(key)
        points = [(float(r["mean_confidence"]), float(r["observed_frequency"]), int(r["count"]))
                  for r in reliability[reliability.index(r0):reliability.index(r0) + 10]
                  if int(r["count"]) > 0]
        if not points:
            continue
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o",
                label=f"{float(r0['horizon_s']):g} s")
    ax.set_xlabel("stated probability (bin mean)"); ax.set_ylabel("observed frequency")
    ax.set_title("per-robot probability" if quantity == "robot" else "formation confidence")
    ax.legend()
fig.suptitle("Reliability of the model's probabilities")
fig.tight_layout(); fig.savefig(os.path.join(out, "reliability.png"), dpi=110)

# The same for every grid of the paper (grid-sweep), all game states together, each horizon's
# line labelled with its expected calibration error (10 bins). Bins of fewer than 50 predictions
# are left out of the lines (the ECE weighs every bin by its count): a handful of robots at a
# rare probability only draws noise.
# A horizon's own model comes first in the files; the chain's first step, which may have the same
# horizon, after it: each (grid, quantity, horizon) takes its first block of bins and first ECE.
sweep_bins = {}
for r in rows("grid-sweep-reliability.csv"):
    if r["game_state"] != "all" or r["horizon_steps"] != "1":
        continue
    bins = sweep_bins.setdefault((r["grid"], r["quantity"], r["horizon_s"]), [])
    if len(bins) < 10:
        bins.append(r)
sweep_ece = {}
for r in rows("grid-sweep-calibration.csv"):
    if r["game_state"] == "all" and r["horizon_steps"] == "1":
        sweep_ece.setdefault((r["grid"], r["quantity"], r["horizon_s"]), float(r["ece"]))
sweep_grids = list(dict.fromkeys(grid for grid, _, _ in sweep_bins))
fig, axes = plt.subplots(2, len(sweep_grids), figsize=(3.2 * len(sweep_grids), 6.6), squeeze=False)
for row, quantity in enumerate(["robot", "formation"]):
    for column, grid in enumerate(sweep_grids):
        ax = axes[row][column]
        ax.plot([0, 1], [0, 1], color="grey", linestyle=":")
        lines = {horizon: [(float(r["mean_confidence"]), float(r["observed_frequency"]))
                           for r in bins if int(r["count"]) >= 50]
                 for (g, q, horizon), bins in sweep_bins.items() if g == grid and q == quantity}
        for horizon, points in lines.items():
            ece = sweep_ece.get((grid, quantity, horizon), float("nan"))
            ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", markersize=3,
                    label=f"{float(horizon):g} s, ECE {ece:.3f}")
        ax.set_title(f"{grid}: {'robot' if quantity == 'robot' else 'formation'}")
        ax.set_xlim(0, 1); ax.set_ylim(0, 1); ax.legend(fontsize=7, loc="upper left")
        if row == 1: ax.set_xlabel("stated probability")
        if column == 0: ax.set_ylabel("observed frequency")
fig.suptitle("Reliability of the model's probabilities on every grid (held out; bins of 50 or "
             "more predictions)")
fig.tight_layout(); fig.savefig(os.path.join(out, "reliability-by-grid.png"), dpi=100)

sweep = rows("grid-sweep.csv")
grids = [r["grid"] for r in sweep]
fig, axes = plt.subplots(1, 3, figsize=(13, 4))
for key, label in [("model_cell_accuracy_h1", "model"), ("persistence_cell_accuracy_h1", "persistence"),
                   ("constant_velocity_cell_accuracy_h1", "constant velocity"),
                   ("damped_constant_velocity_cell_accuracy_h1", "damped constant velocity")]:
    axes[0].plot(grids, [float(r[key]) for r in sweep], marker="o", label=label)
axes[0].set_title("exact cell, one step"); axes[0].legend()
axes[1].bar(grids, [int(r["table_memory_bytes"]) / 1024 for r in sweep]); axes[1].set_title("table memory (KiB)")
axes[2].bar(grids, [float(r["prediction_us"]) for r in sweep]); axes[2].set_title("2-step prediction (µs)")
fig.suptitle("Grid sweep")
fig.tight_layout(); fig.savefig(os.path.join(out, "grid-sweep.png"), dpi=110)
print("plots written to", out)
PY
