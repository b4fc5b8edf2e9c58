#!/usr/bin/env bash
# Runs ssl-evaluate in its three modes and turns the CSVs into PNG plots:
#   fig4-similarity.png      running averages of the similarity measures (the paper's Figure 4)
#   fig5-confidence.png      running average confidence of the 1st and 2nd prediction (Figure 5)
#   accuracy-vs-horizon.png  model against persistence and constant velocity, horizons 1-3
#   reliability.png          reliability diagram of the formation confidence
#   grid-sweep.png           accuracy, table memory and prediction time per grid
#
#   scripts/plot-eval.sh [OUTPUT_DIR]      (default: build/eval)
# Extra ssl-evaluate options can be given in SSLF_EVAL_OPTIONS, e.g. "--jitter-mm 20".
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

out="${1:-$SSLF_ROOT/build/eval}"
build_dir="${SSLF_BUILD_DIR:-$SSLF_ROOT/build}"
SSLF_PACKAGES+=(python3 python3-matplotlib)
sslf_install_packages
sslf_build "$build_dir" -DCMAKE_BUILD_TYPE=Release >"$build_dir.build.log" 2>&1 || {
  tail -50 "$build_dir.build.log" >&2
  exit 1
}
mkdir -p "$out"
evaluate="$build_dir/predictor/ssl-evaluate"
# shellcheck disable=SC2086
"$evaluate" paper --output-dir "$out" ${SSLF_EVAL_OPTIONS:-} | tee "$out/paper.txt"
# shellcheck disable=SC2086
"$evaluate" holdout --output-dir "$out" ${SSLF_EVAL_OPTIONS:-} | tee "$out/holdout.txt"
# shellcheck disable=SC2086
"$evaluate" grid-sweep --output-dir "$out" ${SSLF_EVAL_OPTIONS:-} | tee "$out/grid-sweep.txt"

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
methods = ["model", "persistence", "constant velocity"]
fig, axes = plt.subplots(1, 3, figsize=(12, 4))
for ax, key, label in zip(axes, ["state_accuracy", "cell_accuracy", "mean_cell_distance"],
                          ["exact state", "exact cell", "cells off per robot"]):
    for m in methods:
        points = [(int(r["horizon"]), float(r[key])) for r in holdout if r["method"] == m]
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", label=m)
    ax.set_xlabel("horizon (steps)"); ax.set_title(label); ax.set_xticks([1, 2, 3])
axes[0].legend()
fig.suptitle("Held-out accuracy: model against baselines")
fig.tight_layout(); fig.savefig(os.path.join(out, "accuracy-vs-horizon.png"), dpi=110)

reliability = rows("holdout-reliability.csv")
fig, ax = plt.subplots(figsize=(5, 5))
ax.plot([0, 1], [0, 1], color="grey", linestyle=":", label="perfect calibration")
for h in ["1", "2"]:
    points = [(float(r["mean_confidence"]), float(r["observed_frequency"]), int(r["formations"]))
              for r in reliability if r["horizon"] == h and int(r["formations"]) > 0]
    brier = float([r for r in reliability if r["horizon"] == h][0]["brier"])
    ax.scatter([p[0] for p in points], [p[1] for p in points], s=[10 + p[2] / 20 for p in points],
               label=f"horizon {h} (Brier {brier:.3f})")
    ax.plot([p[0] for p in points], [p[1] for p in points], alpha=0.5)
ax.set_xlabel("predicted confidence (bin mean)"); ax.set_ylabel("observed frequency")
ax.set_title("Reliability of the formation confidence"); ax.legend()
fig.tight_layout(); fig.savefig(os.path.join(out, "reliability.png"), dpi=110)

sweep = rows("grid-sweep.csv")
grids = [r["grid"] for r in sweep]
fig, axes = plt.subplots(1, 3, figsize=(13, 4))
for key, label in [("model_cell_accuracy_h1", "model"), ("persistence_cell_accuracy_h1", "persistence"),
                   ("constant_velocity_cell_accuracy_h1", "constant velocity")]:
    axes[0].plot(grids, [float(r[key]) for r in sweep], marker="o", label=label)
axes[0].set_title("exact cell, horizon 1"); axes[0].legend()
axes[1].bar(grids, [int(r["table_memory_bytes"]) / 1024 for r in sweep]); axes[1].set_title("table memory (KiB)")
axes[2].bar(grids, [float(r["prediction_us"]) for r in sweep]); axes[2].set_title("2-step prediction (µs)")
fig.suptitle("Grid sweep")
fig.tight_layout(); fig.savefig(os.path.join(out, "grid-sweep.png"), dpi=110)
print("plots written to", out)
PY
