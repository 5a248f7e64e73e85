#!/usr/bin/env bash
# The tables of a machine with an NVIDIA GPU and 16 cores, in one command (BENCHMARKS.md,
# "Full-size dome run"): the variant, the gonio's per-pair time and the dome's stage position
# on the GPU and on the CPUs, the BTF BSDF's decoded table against its PCA factors on the GPU,
# and the distributed capture on 1-16 CPU workers. Each writes JSON into OUT (default
# out/gpu-machine); about 40 minutes on a 16-core machine.
#
# Run from the repository root after `make bootstrap`: bash benchmarks/gpu_machine.sh [OUT]
set -euo pipefail
out="${1:-out/gpu-machine}"
mkdir -p "$out"
python=".venv/bin/python"
run() {  # name, then the command; its JSON into OUT/name.json
  local name="$1"
  shift
  echo "== $name: $*" >&2
  "$@" >"$out/$name.json"
}
run info .venv/bin/spectwin info --json
run gonio_pairs_gpu "$python" -m benchmarks.gonio_campaign --pairs 60
run dome_pose_gpu "$python" -m benchmarks.dome_campaign --program run
run btf_render_gpu "$python" -m benchmarks.btf_render --pixels 256
export SPECTWIN_VARIANT=llvm_ad_spectral
run gonio_pairs_cpu "$python" -m benchmarks.gonio_campaign --pairs 60
run dome_pose_cpu "$python" -m benchmarks.dome_campaign --program run
run distributed_cpu "$python" -m benchmarks.distributed_capture --workers 1 2 4 8 16 --pairs 320
echo "tables in $out" >&2
