#!/usr/bin/env bash
# Quick start command (2): install what is missing, build, run every test (gtest and rostest), print a
# summary, exit non-zero on any failure or if no test ran. .ci/run calls exactly this.
#
# Tests that use the real third-party scene in ../shared/data (beside the clone) run when it is present and
# are skipped otherwise; LASER_RAYCAST_REQUIRE_SHARED_DATA=1 turns its absence into a failure, as
# LASER_RAYCAST_REQUIRE_FUZZ=1 does for the fuzz harnesses (built when clang is installed).
set -euo pipefail

usage() {
  cat <<'EOF'
usage: quickstart/test.sh [--sanitize [address|thread]] [--help]

Installs the Debian packages that are missing (apt-get, as root), builds the package in .ws/ inside
the clone, runs every test (gtest and rostest) and catkin_lint -W2, and prints the summary. Exits
non-zero on any failure or if no test ran. CI (.ci/run) runs exactly this.

  --sanitize  build with AddressSanitizer and UndefinedBehaviorSanitizer in a workspace under
              $TMPDIR or /tmp (its path is printed) and run the same tests there (not the fuzz
              harnesses: they are sanitized builds already); a sanitizer report fails the test
              that caused it
  --sanitize thread
              the same with ThreadSanitizer (a workspace of its own): a data race stops the
              process that found it; test/sanitizer/tsan.supp lists the third-party code whose
              reports are suppressed

Environment:
  LASER_RAYCAST_REQUIRE_SHARED_DATA=1  fail instead of skipping when ../shared/data is missing
  LASER_RAYCAST_REQUIRE_FUZZ=1         fail instead of skipping when the fuzz harnesses were not
                                       built (no clang; not with --sanitize, which leaves them out)
  LASER_RAYCAST_WS=DIR                 build in DIR instead of .ws/ (or the sanitize workspace;
                                       never inside the clone)
  LASER_RAYCAST_JOBS=N                 parallel build jobs (default: the number of CPUs)
  LASER_RAYCAST_FUZZ_SEED=N            the fuzz smoke test's seed (default fixed; 0: random)
  LASER_RAYCAST_FUZZ_RUNS=N            inputs per fuzz harness in test_fuzz_smoke
  LASER_RAYCAST_FUZZ_SECONDS=N         time bound per fuzz harness in test_fuzz_smoke
EOF
}
sanitize=0
sanitizer=address
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  --sanitize)
    sanitize=1
    case "${2:-address}" in
      address|thread) sanitizer=${2:-address} ;;
      *) echo "quickstart/test.sh: --sanitize takes address or thread, not '$2'" >&2; exit 2 ;;
    esac
    [ $# -le 2 ] || { echo "quickstart/test.sh: too many arguments (try --help)" >&2; exit 2; } ;;
  "") ;;
  *) echo "quickstart/test.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
esac
[ $# -le 1 ] || [ $sanitize -eq 1 ] ||
  { echo "quickstart/test.sh: one argument at most (try --help)" >&2; exit 2; }

if [ $sanitize -eq 1 ]; then
  # A workspace of its own, so that the normal build stays as it is, and outside the clone: rosrun
  # searches the package's source tree for executables, and a second devel space in it makes every
  # `rosrun laser_raycast ...` of the rostests ambiguous (in both builds).
  repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  suffix=$([ "$sanitizer" = thread ] && echo _thread || true)
  : "${LASER_RAYCAST_WS:=${TMPDIR:-/tmp}/laser_raycast_ws_sanitize${suffix}_$(printf %s "$repo" | cksum | cut -d' ' -f1)}"
  export LASER_RAYCAST_WS
fi
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if [ $sanitize -eq 1 ] && [ "$sanitizer" = thread ]; then
  BUILD_TYPE=RelWithDebInfo
  CMAKE_OPTIONS=(-Dlaser_raycast_SANITIZE_THREAD=ON -Dlaser_raycast_FUZZ=OFF)
  # A race stops the process (the node dies, its rostest fails); reports in third-party code only
  # are suppressed, each with its reason (test/sanitizer/tsan.supp).
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
  TSAN_OPTIONS+=":suppressions=$REPO_DIR/test/sanitizer/tsan.supp"
  # The nodelet manager is Debian's, not instrumented: the TSan runtime must be loaded into it.
  export LASER_RAYCAST_NODELET_PREFIX="env LD_PRELOAD=$(gcc -print-file-name=libtsan.so)"
  # So is the Python interpreter of the rospy client test (node_edit.test), for the module.
  export LASER_RAYCAST_PYTHON_PREFIX="env LD_PRELOAD=$(gcc -print-file-name=libtsan.so)"
elif [ $sanitize -eq 1 ]; then
  BUILD_TYPE=RelWithDebInfo
  CMAKE_OPTIONS=(-Dlaser_raycast_SANITIZE=ON -Dlaser_raycast_FUZZ=OFF)
  # Undefined behaviour stops the program (compiled with -fno-sanitize-recover); leaks are
  # reported at exit, except those of the ROS libraries listed in test/sanitizer/lsan.supp.
  export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export LSAN_OPTIONS=suppressions=$REPO_DIR/test/sanitizer/lsan.supp:print_suppressions=0
  # The nodelet manager is Debian's, not instrumented: the ASan runtime must come first in it.
  export LASER_RAYCAST_NODELET_PREFIX="env LD_PRELOAD=$(gcc -print-file-name=libasan.so)"
fi

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
