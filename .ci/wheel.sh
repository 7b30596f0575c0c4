#!/usr/bin/env bash
# The wheel outside the source tree: build it, install it with its dependencies from the package
# index into a fresh virtualenv, and draw from another folder with the shipped shaders, presets
# and example model. Takes minutes (it downloads the dependencies), so it is not in the tests.
#   .ci/wheel.sh [PYTHON]
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:-python3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$python" -m pip wheel . --no-deps -q -w "$work/wheel"
wheel=$(ls "$work"/wheel/blueprint_drawings-*.whl)
"$python" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install -q "$wheel"
cd "$work"
"$work/venv/bin/blueprint" --version
"$work/venv/bin/python" - <<'PY'
import importlib.resources as res
from pathlib import Path

import blueprint
from blueprint import examples

here = Path(blueprint.__file__).resolve()
assert "site-packages" in here.parts, f"blueprint imported from {here}, not from the wheel"
gearbox = examples.example_path()
assert gearbox.is_file(), gearbox
drawing = blueprint.draw(gearbox, size=(256, 192))
assert drawing.image.shape == (192, 256, 4) and drawing.layers >= 2, drawing.layers
for suffix in ("png", "svg", "pdf", "dxf"):
    assert drawing.save(f"gearbox.{suffix}").stat().st_size > 0
print("drew", gearbox.name, "in", drawing.layers, "layers from", here.parent)
PY
"$work/venv/bin/blueprint" render "$("$work/venv/bin/python" -c 'from blueprint import examples; print(examples.example_path())')" -o "$work/cli.png" --size 256 192
"$work/venv/bin/blueprint" batch "$work"/venv/lib/python*/site-packages/blueprint/data -o "$work/batch" --formats png,svg --size 128 96
echo "wheel ok: $(basename "$wheel")"
