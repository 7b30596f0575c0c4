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

# each Python's virtualenv made and the wheel installed into it side by side (mostly unpacking
# and waiting on the package index), then the smoke tests one after another
install() {
    local python=$1 venv=$2 log=$3 start=$SECONDS
    # -qq: the package index's configuration warns of every name its local mirrors lack
    if "$python" -m venv "$venv" > "$log" 2>&1 && "$venv/bin/python" -m pip install -qq "$wheel" >> "$log" 2>&1; then
        echo "wheel: $4: installed with its dependencies in $((SECONDS - start)) s" >> "$log.done"
    else
        echo "wheel: $4: installing the wheel failed" >> "$log.done"
    fi
}
versions=()
for python in "${pythons[@]}"; do
    version=$("$python" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])')
    [[ " ${versions[*]} " == *" $version "* ]] && continue  # one venv a version
    versions+=("$version")
    install "$python" "$work/venv-$version" "$work/install-$version.log" "Python $version" &
done
wait

failed=()
for version in "${versions[@]}"; do
    cat "$work/install-$version.log.done"
    if grep -q "failed" "$work/install-$version.log.done"; then
        tail -5 "$work/install-$version.log"
        failed+=("$version")
        continue
    fi
    venv="$work/venv-$version"
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
echo "wheel: ok on ${#versions[@]} Python versions"
