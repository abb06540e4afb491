#!/usr/bin/env bash
# Wheels that the GPU machine lacks, for benchmarks/gpu_machine.sh (run this on the development
# machine; the GPU machine reaches no package registry).
#
#   bash benchmarks/gpu_wheels.sh [DEST]          # default DEST: .whl
#
# The GPU machine has had Python 3.12 with CUDA torch, numpy and numba (check with
# `bash benchmarks/gpu_machine.sh probe`); everything else demseis needs to generate, load and
# train is downloaded here for CPython 3.12 on x86-64 Linux: zarr, numcodecs, dask, distributed,
# scipy, tqdm, segyio and their dependencies. numpy, numba, llvmlite and torch are left out (the
# machine's own are used), and so is matplotlib (no figure is drawn there): about 45 MB, which
# with the checkout (~12 MB) fits the 64 MiB that `run` carries. Put DEST in .git/info/exclude
# and pass it in `carry`.
set -euo pipefail
dest=${1:-.whl}
mkdir -p "$dest"
pip download --quiet --python-version 3.12 --only-binary=:all: \
    --platform manylinux2014_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux_2_28_x86_64 -d "$dest" \
    "zarr>=3.1,<3.2" "dask[distributed]>=2024.1" "tqdm>=4.66" "segyio>=1.9" "scipy>=1.11" \
    "psutil" "numpy>=1.26"
# the machine's own numpy / numba / torch are used (a second numpy would shadow the one they
# were built against)
rm -f "$dest"/numpy-*.whl "$dest"/numba-*.whl "$dest"/llvmlite-*.whl "$dest"/torch-*.whl
du -sh "$dest"
