#!/bin/sh
# The test suite: set up the MicroPython unix port (boards/unix.sh), run every tests/test_*.py
# on it, one process a module and several at once, the seven that look at what loading a .mpy
# changes (MPY, in this file) again against the .mpy files mpy-cross makes of lib/, those that
# the computer's side shares (CPY) again on CPython (tests/cpython.py), check the
# style and the types, check that the checkout is as it was (no test writes outside a scratch
# folder of its own), and end with the line "N passed, N failed" (", N skipped" when some
# were). Exits non-zero if any test failed or any module did not run to its end.
#
#   sh tests/run.sh                            # all of it
#   sh tests/run.sh test_frames test_queries   # those modules (tests/test_frames.py too)
#   sh tests/run.sh style types                # the style (ruff) and the types (mypy) alone
#   sh tests/run.sh -k battery                 # the tests whose name holds "battery" (or
#                                              #   whose class's name does), in every module
#   sh tests/run.sh -v                         # every test's line, not one a module
#   sh tests/run.sh -j 1                       # one module at a time (default: the cores + 1)
#   sh tests/run.sh --mpy-all                  # every module against the .mpy files too
#   sh tests/run.sh --help                     # this text (also -h)
#
# A module that passed gets a line (and one a skip); one that failed, all its output. The
# failed tests are named again just above the last line. Each module's output waits in a
# scratch folder until it is printed, in the order of the modules above, whatever order they
# end in. Each module runs with HOME and TMPDIR in a folder of its own (removed after it), so
# that what a tool writes there by itself (the REPL's history, Chromium's crash reports) is
# neither the user's nor another run's.
set -u
usage() {
    sed -n '2,/^[^#]/s/^# \{0,1\}//p' "$0"
}
die() {
    echo "tests/run.sh: $1 (sh tests/run.sh --help)" >&2
    exit 2
}
cd "$(dirname "$0")/.."

# The .mpy pass. boards/unix.sh --mpy compiles lib/*.py with mpy-cross at its default
# optimisation, as the unix port compiles a .py itself (line numbers and asserts kept): what a
# module does is the same from either. What the .mpy changes is how a module is loaded: no
# compile on the board, the .mpy's own format, a __file__ that ends in .mpy, and what is looked
# for beside it (the web panel's page). So this pass runs, for each module in lib/, one test
# module that imports it and looks at those: test_commands (busservo, that its __file__ is the
# .mpy, and that a traceback from inside it names the line), test_sim (busservo_sim, and
# busservo_board's fall-back to it), test_async (busservo_async), test_motion
# (busservo_motion), test_arm (busservo_arm), test_calibrate (busservo_calibrate), test_teleop
# (busservo_teleop), test_record (busservo_record) and test_web (busservo_web, and the page it
# serves, found beside the .mpy). The rest would run the same code again. --mpy-all runs every
# module against the .mpy too.
MPY="test_commands test_sim test_async test_motion test_arm test_calibrate test_teleop test_web"
MPY="$MPY test_record"
# The CPython pass: the same modules run on a computer (lib/busservo_cpython.py gives CPython
# what it lacks, tests/cpython.py the tests), labelled "(CPython)": the driver's, the
# simulator's, the wire world's, asyncio's, the motion's, the arm's, the calibration's, the
# teleop's, the recorder's, the panel's and the links' (a computer's USB: test_links), and
# test_host (the serial port through pyserial on
# a pty, the busservo command, pip install .) and test_hid (a USB HID controller through a
# fake hidapi binding, and the real binding with nothing plugged in), which run on CPython
# only (CPY_ONLY). test_wire and test_soak look at the world's own heap and its
# MicroPython-style asyncio: not on CPython.
CPY="test_frames test_commands test_queries test_sim test_reliability test_async test_motion"
CPY="$CPY test_arm test_calibrate test_teleop test_web test_host test_hid test_adversarial"
CPY="$CPY test_record test_web_lifecycle test_links"
CPY_ONLY="test_host test_hid"
# The longest modules start first, so that the short ones fill the other cores meanwhile and
# the run ends soon after its longest module does (in the order of their times, measured).
SLOW="test_soak test_browser test_examples test_web test_board test_host test_reliability"
SLOW="$SLOW test_install"
SLOW="$SLOW test_e2e"
SLOW="$SLOW test_scripts test_bench_web test_arm test_docs test_adversarial"
# The modules on simulated time alone (tests/wire.py's clock: nothing real is waited for) run
# at a lower priority (nice 10): they lose nothing by waiting for a core, and the modules on
# real time beside them (the web panel, the browser, the pty, the examples), which can, get
# one first. test_soak (a day of the panel) takes most of the suite's CPU time.
NICE="test_reliability test_soak test_wire test_motion test_arm test_calibrate test_bench_motion"
NICE="$NICE test_bench_arm test_adversarial test_record"
CODE="lib tests examples boards"
COUNTS="tests/run.sh-counts:"  # the last line of a module's run: tests run, failed, skipped

verbose=""
pattern=""
jobs=""
mpy_all=""
modules=""
checks=""
while [ $# -gt 0 ]; do
    case $1 in
    -h | --help)
        usage
        exit 0
        ;;
    -v) verbose=1 ;;
    -k)
        [ $# -ge 2 ] && [ -n "$2" ] || die "-k wants a PATTERN"
        pattern=$2
        shift
        ;;
    -k?*) pattern=${1#-k} ;;
    -j)
        [ $# -ge 2 ] || die "-j wants a number"
        jobs=$2
        shift
        ;;
    -j?*) jobs=${1#-j} ;;
    --mpy-all) mpy_all=1 ;;
    -*) die "no option $1" ;;
    style | types) checks="$checks $1" ;;
    *)
        name=${1##*/}
        name=${name%.py}
        case $name in
        test_*[!A-Za-z0-9_]* | test_) die "no test module $1" ;;
        test_*) ;;
        *) die "no test module $1: a module's name starts test_" ;;
        esac
        [ -f "tests/$name.py" ] || die "no test module $1 (no tests/$name.py)"
        case " $modules " in *" $name "*) ;; *) modules="$modules $name" ;; esac
        ;;
    esac
    shift
done
case $jobs in
"") ;;
*[!0-9]* | 0*) die "-j wants a number of modules at once, 1 or more, got '$jobs'" ;;
esac
# Nothing named: every module, and the style and the types unless -k picks tests.
if [ -z "$modules$checks" ]; then
    for t in tests/test_*.py; do
        name=${t#tests/}
        modules="$modules ${name%.py}"
    done
    [ -n "$pattern" ] || checks="style types"
fi
selected() {
    case " $modules " in *" $1 "*) return 0 ;; esac
    return 1
}

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

# pip_install PACKAGE MODULE VERSION WHAT-FOR WHAT-SKIPS: PACKAGE==VERSION from PyPI into
# .venv/, unless MODULE is that version already; without it, WHAT-SKIPS skips, saying so.
pip_install() {
    have=$(.venv/bin/python -c "import $2; print($2.__version__)" 2>/dev/null)
    [ "$have" = "$3" ] && return 0
    echo "tests/run.sh: installing $1 $3 into .venv/ ($4)" >&2
    .venv/bin/pip install --disable-pip-version-check -q "$1==$3" >>.venv/setup.log 2>&1 ||
        echo "tests/run.sh: could not install $1: $5 will be skipped" >&2
}

# What the modules chosen need, and only that, so that one module starts at once.
# The web panel's browser tests (tests/browser.py): Selenium (pinned) drives Debian's Chromium
# through its chromedriver; no browser is downloaded.
if selected test_browser; then
    pip_install selenium selenium 4.50.0 "for the browser tests" "the browser tests"
    if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
        apt_install "the browser for the web panel's tests (a few minutes)" chromium \
            chromium-driver ||
            echo "tests/run.sh: could not install chromium: the browser tests will be skipped" >&2
    fi
fi

# pyserial (pinned, as pyproject.toml pins it) for the CPython pass: busservo_host's port.
for name in $CPY; do
    if selected "$name"; then
        pip_install pyserial serial 3.5 "for the computer's serial port" "test_host's port tests"
        break
    fi
done

# hidapi (pinned, as pyproject.toml's hid extra pins it) for test_hid's look at the real binding.
if selected test_hid; then
    pip_install hidapi hid 0.15.0 "for the USB HID controllers" "test_hid's real-binding test"
fi

# resvg-py (a wheel with the resvg renderer compiled in: no system library) lets
# tests/test_docs.py render the wiring pictures.
if selected test_docs; then
    pip_install resvg-py resvg_py 0.5.0 "to render the wiring pictures" \
        "the pictures' rendering test"
fi

passed=0
failed=0
skipped=0

# The failed tests, a line each, for the summary at the end.
failures=""
note_failure() {
    failures="$failures
  $1"
}

# The jobs, numbered in the order they are printed: the modules against lib/*.py, then
# against the .mpy files, then on CPython, then the style, then the types.
n=0
add() {  # KIND NAME
    n=$((n + 1))
    eval "kind_$n=$1 name_$n=$2"
}
for name in $modules; do
    case " $CPY_ONLY " in *" $name "*) continue ;; esac
    add py "$name"
done
with_mpy=""
for name in $modules; do
    case " $MPY " in *" $name "*) ;; *) [ -n "$mpy_all" ] || continue ;; esac
    with_mpy="$with_mpy $name"
done
if [ -n "$with_mpy" ]; then
    if sh boards/unix.sh --mpy >/dev/null; then
        for name in $with_mpy; do
            add mpy "$name"
        done
    else
        echo "mpy-cross failed"
        note_failure "mpy-cross: the .mpy pass did not run"
        failed=$((failed + 1))
    fi
fi
for name in $modules; do
    case " $CPY " in *" $name "*) add cpy "$name" ;; esac
done
for check in style types; do
    case " $checks " in *" $check "*) add "$check" - ;; esac
done

# How many at once: as many as there are cores, and one more, since some modules spend most
# of their time waiting on real time (the examples, the web panel, the browser).
if [ -z "$jobs" ]; then
    jobs=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)
    jobs=$((jobs + 1))
fi

# The order they start in: the longest first, each module's .mpy pass after it.
order=""
for name in $SLOW; do
    i=1
    while [ $i -le $n ]; do
        eval "[ \"\$name_$i\" = $name ]" && order="$order $i"
        i=$((i + 1))
    done
done
i=1
while [ $i -le $n ]; do
    case " $order " in *" $i "*) ;; *) order="$order $i" ;; esac
    i=$((i + 1))
done

# The scratch folder: each job's output (I.out), its exit status (I.rc, once it has ended),
# the folder it runs in (I.home), and a pipe on which each job says it has ended.
tmp=$(mktemp -d "${TMPDIR:-/tmp}/busservo-run.XXXXXX") || exit 1
mkfifo "$tmp/ended" && exec 4<>"$tmp/ended" || exit 1

# kill_tree PID: PID and every process it started, and they started, ...
kill_tree() {
    ps -A -o pid= -o ppid= | awk -v root="$1" '
        { kids[$2] = kids[$2] " " $1 }
        END {
            todo = root
            while (todo != "") {
                n = split(todo, pids, " ")
                todo = ""
                for (i = 1; i <= n; i++) {
                    print pids[i]
                    todo = todo " " kids[pids[i]]
                }
                if (todo ~ /^ *$/) todo = ""
            }
        }' | xargs kill 2>/dev/null
}
# On Ctrl-C (which the jobs, started in the background, do not get), a kill, or any exit:
# stop every job still running, with its process group (what it left in the background: an
# example, Chromium) and what it started that left the group (a simulator behind a pty).
stop_jobs() {
    i=1
    while [ $i -le $n ]; do
        eval "pid=\${pid_$i:-}"
        if [ -n "$pid" ] && [ ! -e "$tmp/$i.rc" ]; then
            group=$(cat "$tmp/$i.pid" 2>/dev/null)
            kill_tree "$pid"
            [ -n "$group" ] && kill -- "-$group" 2>/dev/null
        fi
        i=$((i + 1))
    done
    rm -rf "$tmp"
}
trap 'trap - INT TERM; exit 130' INT
trap 'trap - INT TERM; exit 143' TERM
trap 'stop_jobs' EXIT

# The unittest run of module $1, as `sh boards/unix.sh -c` takes it. unittest.main() is
# called here rather than by the module: micropython-unittest 0.4 ends it with
# sys.exit(failures > 0), which MicroPython prints and turns into exit 1 even when all
# passed. With -k (RUN_SH_K), unittest 0.4 finds a test case's tests with dir(): a dir() of
# unittest's own lists those -k picks and no other. Its last line gives the counts (what
# the tests print may hold other runs' summaries: a failed browser test prints Selenium's).
snippet() {
    echo "import os, sys, unittest
sys.path.append('tests')
k = os.getenv('RUN_SH_K')
if k:
    def picked(o, dir=dir):
        names = dir(o)
        if isinstance(o, unittest.TestCase):
            c = type(o).__name__
            names = [t for t in names if t[:4] != 'test' or k in t or k in c]
        return names

    unittest.dir = picked
results = []
run = unittest.TestRunner.run
unittest.TestRunner.run = lambda self, suite: results.append(run(self, suite)) or results[-1]
try:
    unittest.main('$1')
except SystemExit:
    pass
r = results[-1]
print('$COUNTS', r.testsRun, r.failuresNum + r.errorsNum, r.skippedNum)"
}

# run_job I: job I, its output to I.out, then its exit status to I.rc; then it says so. It
# runs in a process group of its own (I.pid), for stop().
run_job() {
    i=$1
    eval "kind=\$kind_$i name=\$name_$i"
    home=$tmp/$i.home
    mkdir "$home"
    nice=""
    case " $NICE " in *" $name "*) nice="nice -n 10" ;; esac
    lib=""
    [ "$kind" = mpy ] && lib=.venv/mpy
    case $kind in
    py | mpy)
        set -- env HOME="$home" TMPDIR="$home" BUSSERVO_LIB="$lib" $nice \
            sh boards/unix.sh -c "$(snippet "$name")"
        ;;
    style)
        set -- sh -c ".venv/bin/ruff check -q --no-cache $CODE &&
            .venv/bin/ruff format -q --no-cache --check $CODE"
        ;;
    cpy)
        set -- env HOME="$home" TMPDIR="$home" $nice .venv/bin/python tests/cpython.py "$name"
        ;;
    types) set -- sh tests/typecheck.sh ;;
    esac
    .venv/bin/python -c 'import os, sys
os.setpgid(0, 0)
os.execvp(sys.argv[1], sys.argv[1:])' "$@" </dev/null >"$tmp/$i.out" 2>&1 4>&- &
    echo $! >"$tmp/$i.pid"
    wait $!
    echo $? >"$tmp/$i.rc"
    rm -rf "$home"
    echo "$i" >&4
}

# show I: print job I's result, add up its counts and note what failed.
show() {
    eval "kind=\$kind_$1 name=\$name_$1"
    out=$(cat "$tmp/$1.out")
    rc=$(cat "$tmp/$1.rc")
    case $kind in
    style)
        if [ "$rc" = 0 ]; then
            echo "style: ruff ... ok"
            passed=$((passed + 1))
        else
            printf '%s\n' "$out"
            echo "style: ruff ... FAIL (see above; '.venv/bin/ruff format $CODE')"
            note_failure "style: ruff (see its output above)"
            failed=$((failed + 1))
        fi
        return
        ;;
    types)
        # The examples and board files type-check against the driver's stubs (lib/*.pyi),
        # as a maker's editor sees them.
        if [ "$rc" = 0 ]; then
            echo "types: mypy ... ok"
            passed=$((passed + 1))
        else
            printf '%s\n' "$out"
            echo "types: mypy ... FAIL (see above)"
            note_failure "types: mypy (see its output above)"
            failed=$((failed + 1))
        fi
        return
        ;;
    py) label="$name:" pass=.py ;;
    mpy) label="$name (.mpy):" pass=.mpy ;;
    cpy) label="$name (CPython):" pass=CPython ;;
    esac
    # The counts: the snippet's last line, if the module ran to its end (then not shown).
    ran=""
    last=$(printf '%s\n' "$out" | tail -n 1)
    case $last in
    "$COUNTS "*)
        set -f
        set -- $last
        set +f
        ran=$2 bad=$3 skip=$4
        out=$(printf '%s\n' "$out" | sed '$d')
        ;;
    esac
    # Each test's line is "NAME (CLASS) ..." then its verdict, which its own output may have
    # pushed onto a later line. The tracebacks after unittest's "Ran N tests" are not read:
    # that line comes after N tests' lines (a test may print another run's before).
    names=$(printf '%s\n' "$out" | awk -v ran="${ran:--1}" '
        $0 ~ "^Ran " ran " tests?$" && tests == ran { exit }
        match($0, /^test[^ ]* \([^ ]*\) \.\.\./) { name = substr($0, 1, RLENGTH - 4); tests++ }
        / FAIL$/ { print name }')
    [ -n "$pattern" ] && [ "$ran" = 0 ] && return # -k picked none of its tests
    if [ -z "$ran" ] || [ "$bad" != 0 ] || [ -n "$verbose" ]; then
        printf '%s\n' "$out" | sed "s|^|$label |"
    else
        echo "$label $((ran - skip)) passed"
        printf '%s\n' "$out" | grep -i 'skipped' | grep -v '^OK (' | sed "s|^|$label |"
    fi
    if [ -z "$ran" ]; then
        echo "$label did not run to its end"
        last=$(printf '%s\n' "$out" | sed -n 's/^\(test[^ ]* ([^ ]*)\) \.\.\..*/\1/p' | tail -n 1)
        note_failure "$name ($pass): did not run to its end${last:+, in $last}"
        failed=$((failed + 1))
        return
    fi
    passed=$((passed + ran - bad - skip))
    failed=$((failed + bad))
    skipped=$((skipped + skip))
    while IFS= read -r test; do
        [ -z "$test" ] || note_failure "$name ($pass): $test"
    done <<EOF
$names
EOF
}

# The checkout as it stands: each file and folder but .git/ and .venv/ (what the set-up
# installs), and build/ and lib/*.egg-info/ (what the README's `pip install .` writes, which a
# maker may run beside the tests), with its size and time. No test writes outside a scratch
# folder of its own: one that did (a maker's sequences/, teach.json or web_panel.txt
# overwritten, a folder made and removed again) changes it, and the run fails, naming what
# changed.
checkout() {
    find . \( -path ./.git -o -path ./.venv -o -path ./build -o -path './lib/*.egg-info' \) \
        -prune -o -printf '%p %y %s %T@\n' | LC_ALL=C sort
}
checkout >"$tmp/checkout.before"

# Start the jobs, at most $jobs at once, and print each job's result once it and all the
# jobs before it have ended.
RUN_SH_K=$pattern  # (empty: every test, whatever a run.sh that runs this one was given)
export RUN_SH_K
shown=1
show_ended() {
    while [ $shown -le $n ] && [ -e "$tmp/$shown.rc" ]; do
        show $shown
        shown=$((shown + 1))
    done
}
running=0
for i in $order; do
    while [ $running -ge "$jobs" ]; do
        read -r _ <&4
        running=$((running - 1))
        show_ended
    done
    run_job "$i" &
    eval "pid_$i=$!"
    running=$((running + 1))
done
while [ $running -gt 0 ]; do
    read -r _ <&4
    running=$((running - 1))
    show_ended
done
show_ended

checkout >"$tmp/checkout.after"
changed=$(LC_ALL=C comm -3 "$tmp/checkout.before" "$tmp/checkout.after" |
    sed 's/^[[:space:]]*//; s/ [^ ]* [^ ]* [^ ]*$//' | LC_ALL=C sort -u)
if [ -n "$changed" ]; then
    echo "the checkout: changed while the tests ran (a test wrote outside its scratch folder,"
    echo "or a file was edited meanwhile):"
    printf '%s\n' "$changed" | sed 's/^/  /'
    note_failure "the checkout: the run changed what it holds (see above)"
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
