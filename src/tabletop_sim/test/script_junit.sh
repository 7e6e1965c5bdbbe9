# Sourced by the script tests (test_soak.sh, test_fault_matrix.sh): writes their one-case JUnit
# result so that catkin_test_results counts it.
#   script_junit RESULT SUITE CASE FAILURE_MESSAGE LOG...   (an empty message: passed; else the
#   tails of the LOG files go into the failure, colour codes and control characters stripped:
#   XML 1.0 does not allow them)
script_junit() {
  local result="$1" suite="$2" name="$3" fail="$4" body="" details
  shift 4
  if [ -n "$fail" ]; then
    details=$(for f in "$@"; do tail -n 40 "$f" 2>/dev/null; done |
      sed 's/\x1b\[[0-9;]*m//g' | tr -d '\000-\010\013\014\016-\037' | sed 's/]]>/]] >/g')
    body="<failure message=\"$(echo "$fail" | sed 's/&/\&amp;/g; s/</\&lt;/g; s/"/\&quot;/g')\"><![CDATA[$details]]></failure>"
  fi
  mkdir -p "$(dirname "$result")"
  cat > "$result" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="$suite" tests="1" failures="$([ -n "$body" ] && echo 1 || echo 0)" errors="0">
  <testcase classname="$suite" name="$name">$body</testcase>
</testsuite>
XML
}
