# The shell tests' harness (cli_test.sh, viewer_test.sh), sourced: a scratch directory
# removed at exit, and check NAME CONDITION-COMMAND... counting what passed and failed.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0
check() {  # check NAME CONDITION-COMMAND...
    local name=$1; shift
    if "$@"; then passed=$((passed + 1)); echo "ok   $name"; else failed=$((failed + 1)); echo "FAIL $name"; fi
}
