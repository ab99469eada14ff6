#!/usr/bin/env bash
# The mcdem test command: installs what the tests need on a fresh Debian machine (idempotent,
# non-interactive: LIGGGHTS and its headers from apt, MPI, libclang for bindgen), then runs
# formatting, lints and the whole test suite. `.ci/run` calls exactly this script.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(liggghts libliggghts-dev liggghts-doc mpi-default-dev libclang-dev clang)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "mcdem tests: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q "${missing[@]}"
fi

# VTK's Python package: the independent reader the VTK dump test opens mcdem's files with.
python3 -c "import vtk" 2>/dev/null || python3 -m pip install --quiet vtk

cargo fmt --check
# Lints for the plain build (nothing but cargo: library and binaries) and for everything with the
# LIGGGHTS plugin (feature `liggghts`; tests and benches included). The tests' dev-dependencies
# are checked once, in the second run.
cargo clippy --release --lib --bins -- -D warnings
cargo clippy --release --all-targets --features liggghts -- -D warnings
# One test run covers everything: the feature only adds the C++ shim, `mcdem-liggghts` and its tests.
cargo test --release --features liggghts
