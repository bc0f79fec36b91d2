#!/usr/bin/env bash
# Quick start command (1): install what is missing, build, and run the demo headless: a robot drives
# around a furnished room and the simulated laser's scan is summarised once a second.
#   ./quickstart/demo.sh                 20 s, then stop
#   ./quickstart/demo.sh --duration 0    until Ctrl-C
#   ./quickstart/demo.sh --gui           with RViz (installs rviz; needs a display)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

duration=20
gui=false
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration=${2:?--duration needs seconds}; shift 2 ;;
    --gui) gui=true; shift ;;
    -h|--help) sed -n '2,7p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) log "unknown argument '$1' (try --help)"; exit 2 ;;
  esac
done

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
