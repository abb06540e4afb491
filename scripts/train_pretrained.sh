#!/usr/bin/env bash
# The recipe of the model shipped with demseis (demseis/learning/pretrained/fault_unet.pt;
# its card is docs/model.md): 64 runs of the planar preset with 3-10 planar faults at 50-86
# degrees (the steep planar control of benchmarks/field_benchmark.py), then `demseis train`
# for 1200 CPU steps, base 16, seed 0. Retrain it when the data improve, and update the card's
# scores with the field benchmark command it gives. Usage: bash scripts/train_pretrained.sh DIR
set -euo pipefail
dir=${1:?usage: bash scripts/train_pretrained.sh DIR (a folder for the store and the model)}
mkdir -p "$dir"
cat > "$dir/planar_steep.toml" <<'TOML'
[sweep]
n_runs = 64
planar_faults = { dist = "choice", values = [3, 4, 5, 6, 7, 8, 9, 10] }
planar_dip_min_deg = 50.0
planar_dip_max_deg = 86.0
TOML
demseis generate "$dir/planar_steep.toml" --preset planar --out "$dir/P.zarr" --quiet
demseis train "$dir/P.zarr" --out "$dir/fault_unet.pt" --steps 1200 --seed 0 --base 16 \
  --threads 2 --device cpu
echo "copy $dir/fault_unet.pt and $dir/fault_unet.json to demseis/learning/pretrained/"
