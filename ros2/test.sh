#!/usr/bin/env bash
# The ROS 2 node against an independent ROS 2 peer (CycloneDDS from PyPI),
# with no ROS installation: installs a Python environment (cyclonedds,
# pytest, numpy), builds whycode_node and the whycode CLI (release), runs
# the node's unit tests and lint, its latency benchmark, and the peer tests.
# Everything that opens a DDS participant runs in a network namespace that
# holds only loopback, so no packet leaves this machine.
#
#   ros2/test.sh [pytest arguments, e.g. -k restart]
set -euo pipefail
cd "$(dirname "$0")/.."

# The namespace needs `unshare` (util-linux) and `ip` (iproute2).
if ! command -v ip >/dev/null 2>&1 || ! command -v unshare >/dev/null 2>&1; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq iproute2 util-linux >/dev/null
fi

PYTHON=${PYTHON:-python3}
TARGET=${CARGO_TARGET_DIR:-$PWD/target}
VENV=${WHYCODE_ROS2_VENV:-$TARGET/ros2-venv}

if [ ! -x "$VENV/bin/pytest" ] || ! "$VENV/bin/python" -c "import cyclonedds, numpy" 2>/dev/null; then
    "$PYTHON" -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet cyclonedds pytest numpy
fi

cargo build --release --quiet -p whycode-ros2 --bin whycode_node --example latency
# The CLI the node is compared with: this checkout's (or the one WHYCODE_BIN
# names: .ci/run hands on the Rust suite's).
if [ -z "${WHYCODE_BIN:-}" ]; then
    cargo build --release --quiet --bin whycode
    export WHYCODE_BIN="$TARGET/release/whycode"
fi
# .ci/run lints the whole workspace first and says so.
if [ -z "${WHYCODE_LINTED:-}" ]; then
    cargo clippy --quiet -p whycode-ros2 --all-targets -- -D warnings
fi
cargo test --release --quiet -p whycode-ros2

export WHYCODE_NODE="$TARGET/release/whycode_node"
export PYTEST="$VENV/bin/pytest"
export LATENCY="$TARGET/release/examples/latency"
# CycloneDDS (the peer) on loopback only; the node is started with
# ROS_LOCALHOST_ONLY=1, which binds its discovery and traffic to loopback.
export CYCLONEDDS_URI='<General><Interfaces><NetworkInterface name="lo"/></Interfaces></General>'
export ROS_LOCALHOST_ONLY=1
PEER_DIR="$PWD/ros2/tests/peer"

# shellcheck disable=SC2016
unshare -n bash -c '
    set -euo pipefail
    ip link set lo up
    ip link set lo multicast on
    ip route add 224.0.0.0/4 dev lo
    "$LATENCY"
    cd "$0"
    exec "$PYTEST" -q -p no:cacheprovider "${@:1}" .
' "$PEER_DIR" "$@"
