#!/usr/bin/env bash
# Screenshot of rviz on a running co-simulation, as a user sees it: starts a virtual display (Xvfb, software
# GL), launches cosim.launch with rviz:=true on a scene, waits until the run has been going for a while,
# saves the screen and stops everything.
#   scripts/rviz_screenshot.sh <out.png> [scene] [track_model] [seconds to wait]
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
case "${1:-}" in
  -h|--help) sed -n '2,5p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  -*) echo "rviz_screenshot.sh: unknown option $1 (--help for usage)" >&2; exit 2 ;;
esac
out="$(realpath -m "${1:?usage: rviz_screenshot.sh out.png [scene] [track_model] [wait_s]}")"
scene="$(realpath "${2:-$ROOT/config/scenes/paper_demo.yaml}")"
model="${3:-flexible}"
wait_s="${4:-60}"
export ROS_HOME="${ROS_HOME:-$ROOT/output/ros_home}"
export ROS_IP=127.0.0.1
unset ROS_HOSTNAME
port=$((21000 + $$ % 20000))
export ROS_MASTER_URI="http://127.0.0.1:$port"
display=":$((90 + $$ % 9))"
set +u
# shellcheck disable=SC1091
source "$ROOT/devel/setup.bash"
set -u
export LIBGL_ALWAYS_SOFTWARE=1
Xvfb "$display" -screen 0 1280x800x24 >/dev/null 2>&1 &
xvfb=$!
export DISPLAY="$display"
tmp="$(mktemp -d)"
# In a session of its own, so that the cleanup reaches roslaunch's master and nodes as one group.
setsid roslaunch --disable-title -p "$port" "$ROOT/launch/cosim.launch" scene:="$scene" track_model:="$model" \
  rviz:=true output_dir:="$tmp" record:=false >"$tmp/launch.log" 2>&1 &
launch=$!
cleanup() {
  kill -INT -- "-$launch" 2>/dev/null || true
  for _ in $(seq 1 50); do kill -0 -- "-$launch" 2>/dev/null || break; sleep 0.2; done
  kill -9 -- "-$launch" 2>/dev/null || true
  kill "$xvfb" 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
sleep "$wait_s"
mkdir -p "$(dirname "$out")"
import -display "$display" -window root "$out"
echo "screenshot: $out"
# The run's console output beside the picture (a run that failed shows why).
cp "$tmp/launch.log" "${out%.png}.log"
grep -E "FATAL|ERROR|died" "$tmp/launch.log" | head -5 || true
