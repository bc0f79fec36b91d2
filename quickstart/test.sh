#!/usr/bin/env bash
# Quick start command (2): install what is missing, build, run every test (gtest and rostest), print a
# summary, exit non-zero on any failure or if no test ran. .ci/run calls exactly this.
#
# Tests that use the real third-party scene in ../shared/data (beside the clone) run when it is present and
# are skipped otherwise; LASER_RAYCAST_REQUIRE_SHARED_DATA=1 turns its absence into a failure.
set -euo pipefail

usage() {
  cat <<'EOF'
usage: quickstart/test.sh [--help]

Installs the Debian packages that are missing (apt-get, as root), builds the package in .ws/ inside
the clone, runs every test (gtest and rostest) and catkin_lint -W2, and prints the summary. Exits
non-zero on any failure or if no test ran. CI (.ci/run) runs exactly this.

Environment:
  LASER_RAYCAST_REQUIRE_SHARED_DATA=1  fail instead of skipping when ../shared/data is missing
  LASER_RAYCAST_WS=DIR                 build in DIR instead of .ws/
  LASER_RAYCAST_JOBS=N                 parallel build jobs (default: the number of CPUs)
EOF
}
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  "") ;;
  *) echo "quickstart/test.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
esac

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

install_missing "${APT_PACKAGES[@]}"
# A downstream package that links every exported library, built beside this one (test/downstream).
mkdir -p "$WS_DIR/src"
[ -e "$WS_DIR/src/laser_raycast_downstream_check" ] ||
  ln -s "$REPO_DIR/test/downstream" "$WS_DIR/src/laser_raycast_downstream_check"
build_workspace
source_workspace

shared_data=$(cd "$REPO_DIR/.." && pwd)/shared/data
if [ -d "$shared_data/tb3_world_data" ]; then
  export LASER_RAYCAST_SHARED_DATA=$shared_data
  export ROS_PACKAGE_PATH=$ROS_PACKAGE_PATH:$shared_data
  log "using shared test data in $shared_data"
else
  log "no ../shared/data: tests on the TurtleBot3 scene will be skipped"
fi

rm -rf "$WS_DIR/build/test_results"
status=0
(cd "$WS_DIR" && catkin_make -j"$JOBS" run_tests >&2) || status=$?
if [ $status -ne 0 ]; then
  log "building or running the tests failed (catkin_make run_tests exit $status)"
fi

# The package's CMake and manifest, linted as a catkin package (-W2: notices too).
if ! (cd "$WS_DIR/src" && catkin_lint -W2 --strict laser_raycast laser_raycast_downstream_check >&2); then
  log "catkin_lint -W2 found problems (above)"
  status=1
fi

summary=$(catkin_test_results --verbose "$WS_DIR/build/test_results") || status=1
echo "$summary"
total=$(echo "$summary" | sed -n 's/^Summary: \([0-9]*\) tests.*/\1/p' | tail -n 1)
if [ -z "$total" ] || [ "$total" -eq 0 ]; then
  log "FAILED: no tests ran"
  exit 1
fi
if [ $status -ne 0 ]; then
  log "FAILED"
  exit 1
fi
log "all $total tests passed"
