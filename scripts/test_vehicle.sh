#!/usr/bin/env bash
# `make test-vehicle`: the vehicle side's tests on the Python of a ROS 2 distribution (3.10:
# Humble, Ubuntu 22.04; 3.12: Jazzy, Ubuntu 24.04), in a venv of their own (.venv-vehicle310/,
# .venv-vehicle312/) that holds what a vehicle installs (vehicle/pyproject.toml: codec, planner,
# vehicle_contract, onboard; pip-installed as on a vehicle) and the tests' tools (its `test`
# extra), nothing of the console. Which tests, and why not the others: tests/vehicle_side.py.
#
#   scripts/test_vehicle.sh 3.10 [pytest args]   build or update the venv, check it, run the tests
#   scripts/test_vehicle.sh --python 3.10        print the interpreter it would use (exit 1: none)
#
# The interpreter: $PYTHON310 (PYTHON312, ...) if set, else pyenv's newest build of that version
# (these machines; .ci/run installs one), else python3.10 on PATH.
set -euo pipefail
cd "$(dirname "$0")/.."

# A usable interpreter: the right version, able to make a venv with pip (Debian splits that
# off: python3.X-venv).
usable() {
  "$1" -c "import sys, ensurepip, venv
sys.exit(sys.version_info[:2] != tuple(map(int, '$2'.split('.'))))" 2>/dev/null
}

find_python() {
  local version=$1 named candidate builds
  named="PYTHON${version//./}"
  if [ -n "${!named:-}" ]; then  # named: that one or none
    usable "${!named}" "$version" && echo "${!named}" && return 0
    echo "$named=${!named} is not a Python $version with venv and ensurepip" >&2
    return 1
  fi
  mapfile -t builds < <(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$version".*/bin/python"$version" \
    2>/dev/null | sort -V -r)
  for candidate in "${builds[@]}" "$(command -v "python$version" || true)"; do
    if [ -n "$candidate" ] && usable "$candidate" "$version"; then
      echo "$candidate"
      return 0
    fi
  done
  return 1
}

if [ "${1:-}" = "--python" ]; then
  find_python "${2:?usage: $0 --python 3.10}"
  exit
fi
version=${1:?usage: $0 VERSION [pytest args], e.g. $0 3.10}
shift
venv=.venv-vehicle${version//./}
# Only what the venv holds (a developer's shell may point PYTHONPATH at a checkout).
unset PYTHONPATH PYTHONHOME
root=$PWD
SECONDS=0

if ! python=$(find_python "$version"); then
  cat >&2 <<EOF
test-vehicle: no Python $version found. The vehicle side is tested on the Python of each ROS 2
it runs on (3.10: Humble, Ubuntu 22.04; 3.12: Jazzy, Ubuntu 24.04). Get one:
  - pyenv install $version   (what .ci/run does; pyenv: https://github.com/pyenv/pyenv), or
  - sudo apt install python$version python$version-venv   (Ubuntu releases that ship it;
    the deadsnakes PPA for the others),
or name one: PYTHON${version//./}=/path/to/python$version make test-vehicle
EOF
  exit 1
fi

# The tools (the `test` extra) when the venv is new or vehicle/pyproject.toml changed.
if [ ! -x "$venv/bin/python" ] || [ vehicle/pyproject.toml -nt "$venv/.installed" ]; then
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --upgrade pip "setuptools>=77"
  "$venv/bin/python" -m pip install --quiet "./vehicle[test]"
  touch "$venv/.installed"
fi
# The vehicle side itself on every run, as a vehicle installs it (a copy: the checkout's code now).
"$venv/bin/python" -m pip install --quiet --no-deps --no-build-isolation --force-reinstall ./vehicle
rm -rf vehicle/build vehicle/*.egg-info  # setuptools' in-tree leftovers: copies of the packages

# Installed, it imports on its own (outside the checkout), the node's core with it, and the
# console is not there.
(cd "$venv" && PYTHONPATH="$root/ros2/nemesys_vehicle" bin/python -c "
import importlib.util, sys
import codec, planner, onboard.agent, onboard.guidance, vehicle_contract.contract
import nemesys_vehicle.core, nemesys_vehicle.convert, nemesys_vehicle.serial_input
for name in ('codec', 'planner', 'vehicle_contract', 'onboard'):
    assert 'site-packages' in sys.modules[name].__file__, sys.modules[name]
for name in ('rosbridge', 'station', 'sim', 'backend', 'bench', 'analysis', 'cli'):
    assert importlib.util.find_spec(name) is None, f'{name} is installed on the vehicle side'
")

# The tests import the checkout's code, the same as the copy just installed (pytest puts the
# repository's root first on sys.path, as in the project's suite: tests/ is a package); the
# check above is what shows the installed distribution complete and alone.
echo "test-vehicle: Python $("$venv/bin/python" -c 'import platform; print(platform.python_version())') ($python)"
"$venv/bin/python" -m pytest --vehicle-side -q -p no:cacheprovider "$@"
echo "test-vehicle: Python $version done in ${SECONDS} s"
