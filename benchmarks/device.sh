#!/usr/bin/env bash
# One device run: set up OpenGL and wheels, check a render, then time blueprint, its code-path
# variants, streamed drawings a second and capture in compute against the graphics pipeline, the
# textbook baseline, the extra features, vector drawings, generated models of growing size
# (benchmarks/scale.py) and what their vector drawings hold by phase
# (benchmarks/vector_memory.py). The wheels a bare H200 lacks come from
#   bash ../shared/tools/device-gl-prep fpdf2==2.8.9 ezdxf==1.4.5 pikepdf==10.18.0 lxml==6.2.0 \
#     defusedxml==0.7.1 fonttools==4.68.0 pyparsing==3.3.3
# (vector drawings write PDF layers with pikepdf). Models come in .models/ (copied from
# ../shared/models).
# Run on the device as: bash benchmarks/device.sh   (carry .gl .whl .models)
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl || exit 1
export PYTHONPATH=$PWD/src:/tmp/site PYTHONUNBUFFERED=1
# the device's shell sets PYTHONDONTWRITEBYTECODE: compiled once here, as an installed wheel is,
# not again in every timed process
python3 -m compileall -q src /tmp/site > /dev/null
export __EGL_VENDOR_LIBRARY_FILENAMES=${__EGL_VENDOR_LIBRARY_FILENAMES:-/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json}
bp() { python3 -c 'from blueprint.cli import main; main()' "$@"; }
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
bp info || exit 1
bp render src/blueprint/data/gearbox.glb -o $OUT/gearbox_gpu.png --size 1024 768
bp render .models/2CylinderEngine.glb -o $OUT/engine_gpu.png --size 1024 1024 --max-layers 0
models=".models/rocker-arm.obj .models/featuretype.STL .models/stanford-bunny.obj .models/2CylinderEngine.glb .models/cycloidal.glb .models/dragon.ply"
bp bench $models --size 512 512 --size 1024 1024 --max-layers 5 --max-layers 0 --frames 20 --warmup 3 > $OUT/bench_ss2.jsonl
bp bench $models --size 512 512 --size 1024 1024 --max-layers 5 --frames 20 --warmup 3 --supersample 1 > $OUT/bench_ss1.jsonl
python3 benchmarks/textbook.py $models --size 512 512 --size 1024 1024 --max-layers 5 --max-layers 256 --frames 20 --warmup 3 > $OUT/textbook.jsonl
python3 benchmarks/features.py .models/2CylinderEngine.glb --highlight "Piston*" --size 1024 1024 > $OUT/features.jsonl
python3 benchmarks/layers.py .models/rocker-arm.obj .models/cycloidal.glb .models/2CylinderEngine.glb > $OUT/layers.jsonl
python3 benchmarks/variants.py .models/rocker-arm.obj .models/cycloidal.glb --frames 30 > $OUT/variants.jsonl
python3 benchmarks/stream.py .models/rocker-arm.obj --size 512 --supersample 1 --max-layers 5 --frames 600 > $OUT/stream_crank.jsonl
python3 benchmarks/stream.py .models/cycloidal.glb .models/2CylinderEngine.glb --size 1024 2048 --max-layers 0 --frames 30 > $OUT/stream.jsonl
python3 benchmarks/compute_capture.py .models/rocker-arm.obj .models/cycloidal.glb .models/2CylinderEngine.glb > $OUT/compute_capture.jsonl
python3 benchmarks/table1.py --models-dir .models --frames 20 --cpu-frames 1 > $OUT/table1.jsonl
python3 benchmarks/vector.py --models-dir .models --runs 3 > $OUT/vector.jsonl
python3 benchmarks/scale.py --size 2048 2048 --sizes scan=1310720,5242880,20971520 --sizes assembly=5,10,20 \
  --sizes parts=100000 --timeout 300 --workdir /tmp/scale > $OUT/scale.jsonl
# a vector drawing's host memory by phase, where the GPU's buffers are not in the process
engines="/tmp/scale/assembly-2CylinderEngine-5x5.glb /tmp/scale/assembly-2CylinderEngine-10x10.glb"
python3 benchmarks/vector_memory.py $engines --size 1024 1024 > $OUT/vector_memory.jsonl
python3 benchmarks/vector_memory.py $engines --size 2048 2048 >> $OUT/vector_memory.jsonl
python3 benchmarks/summary.py $OUT/*.jsonl
