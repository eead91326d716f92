#!/usr/bin/env bash
# The storm learner trained on the GPU and on the CPU of one machine, same seed, same episodes,
# side by side, then both networks flown through the same validation storms (the GPU check).
#
#   bash benches/train_device.sh OUT [EPISODES] [STORMS]
#
# OUT gets train_cuda.log, train_cpu.log and summary.json: each run's training seconds and
# its networks' success and mean excess cost over the exact optimum on the storms STORMS
# (validation seeds, default 900000-900004; 20 fixed starts each, the task's destination).
# The runs themselves go to a temporary folder (their checkpoints hold the replay memory).
# Needs a CUDA device; the two runs train at once (each uses one CPU thread for torch, the
# map builds share the rest).
set -euo pipefail
out=${1:?usage: train_device.sh OUT [EPISODES] [STORMS]}
episodes=${2:-1500}
storms=${3-900000-900004}  # '' : only each run's own evaluation
starts=${STARTS:-20}
py=${PYTHON:-python3}
devices=${DEVICES:-cuda cpu}  # DEVICES=cpu: a dry run on a machine with no GPU
mkdir -p "$out"
runs=$(mktemp -d)
export PYTHONUNBUFFERED=1
[[ $devices != *cuda* ]] || $py -c "import torch; assert torch.cuda.is_available(), 'no CUDA device'; print(torch.__version__, torch.cuda.get_device_name(0))"
for dev in $devices; do
    $py -m rainuav.train --preset storms --dqn.episodes "$episodes" \
        --device "$dev" --out "$runs/$dev" --eval-starts "$starts" >"$out/train_$dev.log" 2>&1 &
done
wait
for dev in ${storms:+$devices}; do
    $py -m rainuav.evaluate "$runs/$dev" --storm-seeds "$storms" --device cpu \
        --out "$runs/eval_$dev" >"$out/eval_$dev.log" 2>&1 &
done
wait
$py - "$runs" "$out" "$episodes" "$storms" "$devices" <<'EOF'
import json, pathlib, sys
runs, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
episodes, storms = sys.argv[3:5]
summary = {"episodes": int(episodes), "storms": storms}
for dev in sys.argv[5].split():
    m = json.loads((runs / dev / "metrics.json").read_text())
    keys = ("success_rate", "mean_excess_cost", "straight_line_mean_excess_cost")
    summary[dev] = {
        "training_seconds": m["training_seconds"],
        "device": m["device"],
        "own_evaluation": {"storm": m["evaluated_on_storm_seed"], "starts": m["eval_starts"]}
        | {k: m[k] for k in keys},
    }
    if storms:
        e = json.loads((runs / f"eval_{dev}" / "evaluation.json").read_text())["mean"]
        summary[dev]["storms_evaluation"] = {k: e[k] for k in keys}
(out / "summary.json").write_text(json.dumps(summary, indent=1))
print(json.dumps(summary, indent=1))
EOF
