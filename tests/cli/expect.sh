# Sourced by the CLI test scripts: `expect CODE PATTERN -- command...` runs the command and checks
# its exit code and that its output matches PATTERN (extended regex, case-insensitive); `check
# DESCRIPTION -- command...` counts a plain assertion. Both count into $passed and $fail.
fail=0 passed=0
expect() {
    local code=$1 pattern=$2; shift 3
    local out rc
    out=$("$@" 2>&1); rc=$?
    if [ "$rc" -ne "$code" ] || ! grep -qiE "$pattern" <<<"$out"; then
        echo "FAIL: '$*' exited $rc (want $code), output: $out"; fail=$((fail + 1))
    else
        passed=$((passed + 1))
    fi
}
check() {
    local what=$1; shift 2
    if "$@"; then passed=$((passed + 1)); else echo "FAIL: $what"; fail=$((fail + 1)); fi
}
