#!/usr/bin/env bash
# The package as users install it: build the wheel once (as pip builds it, in isolation), then for
# each PYTHON install it with its dependencies and no test extras into a fresh virtualenv and run
# .ci/smoke.py from a folder outside the source tree: every command and major option, each case
# checked by what it wrote, one line per case. Exits 1 if any Python's smoke test failed.
#   .ci/wheel.sh [PYTHON...]     (default: python3)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
pythons=("${@:-python3}")

# a copy of the project: setuptools writes its build folders into the tree it builds
mkdir "$work/project"
tar -c --exclude=__pycache__ --exclude='*.egg-info' pyproject.toml README.md LICENSE src | tar -x -C "$work/project"
start=$SECONDS
"${pythons[0]}" -m pip wheel "$work/project" --no-deps -qq -w "$work/wheel"
wheel=$(ls "$work"/wheel/blueprint_drawings-*.whl)
echo "wheel: built $(basename "$wheel") in $((SECONDS - start)) s"

failed=()
for python in "${pythons[@]}"; do
    version=$("$python" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])')
    venv="$work/venv-$version"
    start=$SECONDS
    "$python" -m venv "$venv"
    # -qq: the package index's configuration warns of every name its local mirrors lack
    if ! "$venv/bin/python" -m pip install -qq "$wheel"; then
        echo "wheel: Python $version: installing the wheel failed"
        failed+=("$version")
        continue
    fi
    echo "wheel: Python $version: installed with its dependencies in $((SECONDS - start)) s"
    mkdir "$work/smoke-$version"
    start=$SECONDS
    if ! (cd "$work/smoke-$version" && "$venv/bin/python" "$root/.ci/smoke.py"); then
        failed+=("$version")
    fi
    echo "wheel: Python $version: smoke test took $((SECONDS - start)) s"
done
if [ ${#failed[@]} -gt 0 ]; then
    echo "wheel: failed on Python ${failed[*]}"
    exit 1
fi
echo "wheel: ok on ${#pythons[@]} Python versions"
