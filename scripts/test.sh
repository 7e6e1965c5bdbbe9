#!/usr/bin/env bash
# README command 2: sets everything up if needed, builds and runs every test (gtest unit tests
# of the core libraries and rostest integration tests of the nodelets), then prints the summary.
# Exits non-zero if any test failed or none ran.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
# shellcheck source=ros_env.sh
source "$ROOT/scripts/ros_env.sh"
cd "$ROOT"
export ROS_LOG_DIR="$ROOT/build/test_logs"
# As setup.sh: the cache keyed on paths relative to the checkout's parent.
export CCACHE_DIR="${CCACHE_DIR:-$HOME/.ccache}" CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$ROOT")}"
rm -rf build/test_results
echo "[test] building and running the tests"
set +e
catkin_make tests -j2 2>&1 | grep --line-buffered -E 'error|Error|warning: unused|Linking' 
build_rc=${PIPESTATUS[0]}
if [ "$build_rc" -ne 0 ]; then echo "[test] ERROR: building the tests failed"; exit 1; fi
# -j1: integration tests measure frame rates and must not compete with each other.
catkin_make run_tests -j1 2>&1 |
  grep --line-buffered -v -E '^-- |^Scanning dependencies|^\[ *[0-9]+%\] Built target|^#### '
set -e
echo
echo "[test] results"
summary=$(catkin_test_results --verbose build/test_results 2>&1) || true
echo "$summary" | grep -v -E '^$' | tail -n 60
line=$(echo "$summary" | grep -E '^Summary:' | tail -n 1)
tests=$(echo "$line" | sed -n 's/.*Summary: \([0-9]*\) tests.*/\1/p')
errors=$(echo "$line" | sed -n 's/.* \([0-9]*\) errors.*/\1/p')
failures=$(echo "$line" | sed -n 's/.* \([0-9]*\) failures.*/\1/p')
skipped=$(echo "$line" | sed -n 's/.* \([0-9]*\) skipped.*/\1/p')
tests=${tests:-0}; errors=${errors:-0}; failures=${failures:-0}; skipped=${skipped:-0}
failed=$((errors + failures))
passed=$((tests - failed - skipped))
echo "tests: $passed passed, $failed failed, $skipped skipped"
if [ "$tests" -eq 0 ]; then echo "[test] ERROR: no test ran"; exit 1; fi
if [ "$failed" -ne 0 ]; then exit 1; fi
