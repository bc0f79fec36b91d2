#!/usr/bin/env bash
# Quick start command (1): install what is missing, build, and run the demo headless: a robot drives
# around a furnished room and the simulated laser's scan is summarised once a second.
set -euo pipefail

usage() {
  cat <<'EOF'
usage: quickstart/demo.sh [--duration SECONDS] [--gui] [--help]

Installs the Debian packages that are missing (apt-get, as root), builds the package in .ws/ inside
the clone, and runs launch/demo.launch: a robot drives around a furnished room and the simulated
laser's scan is summarised once a second.

  --duration SECONDS  stop after this long (default 20; 0: until Ctrl-C)
  --gui               also start RViz (installs rviz; needs a display)
  -h, --help          print this and exit

Exit status: 0 the demo received scans, 1 it did not (or the build failed), 2 bad arguments.
EOF
}

duration=20
gui=false
while [ $# -gt 0 ]; do
  case "$1" in
    --duration)
      if [ $# -lt 2 ] || ! [[ $2 =~ ^[0-9]+([.][0-9]+)?$ ]]; then
        echo "quickstart/demo.sh: --duration needs a number of seconds >= 0 (try --help)" >&2
        exit 2
      fi
      duration=$2; shift 2 ;;
    --gui) gui=true; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "quickstart/demo.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

packages=("${APT_PACKAGES[@]}")
[ "$gui" = true ] && packages+=(rviz)
install_missing "${packages[@]}"
build_workspace
source_workspace

log "running the demo (duration ${duration} s; 0 = until Ctrl-C)"
demo_log=$(mktemp /tmp/laser_raycast_demo.XXXXXX.log)
# Our nodes' lines, without roslaunch's start-up chatter; the whole log stays in $demo_log.
set +e
ROSCONSOLE_STDOUT_LINE_BUFFERED=1 roslaunch laser_raycast demo.launch duration:="$duration" gui:="$gui" 2>&1 |
  tee "$demo_log" |
  grep --line-buffered -E '^\[demo\]|model .*links|ERROR|FATAL|WARN'
set -e
if grep -qE '^\[demo\] [1-9][0-9]* scans received' "$demo_log" || [ "$duration" = 0 ]; then
  log "demo finished (full log: $demo_log)"
else
  log "the demo received no scan (full log: $demo_log)"
  exit 1
fi
