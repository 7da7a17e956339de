#!/bin/sh
# Type-check examples/*.py and boards/*.py against the driver's stubs (lib/*.pyi), as the editors
# makers use (VS Code/Pylance, PyCharm, Thonny) see them, with a pinned mypy installed into
# .venv/ (once). Prints mypy's result; exits non-zero on any type error.
#
# MYPYPATH is lib:boards:tests/stubs. In lib/, busservo.pyi takes precedence over busservo.py.
# tests/stubs/ holds the MicroPython modules CPython's typeshed lacks (machine, board) or has
# in another form (time, asyncio, termios, gc: it shadows those). A few MicroPython-isms that
# typeshed's own os and io contradict are let through, module by module, below.
set -u
cd "$(dirname "$0")/.."
MYPY=2.4.1  # the newest mypy for Python 3.11 (the venv's) when this was written
VENV=.venv
LOG=$VENV/setup.log
sh boards/unix.sh --setup || exit 1

if [ "$($VENV/bin/python -m mypy --version 2>/dev/null | cut -d ' ' -f 2)" != "$MYPY" ]; then
    echo "tests/typecheck.sh: installing mypy $MYPY into $VENV/" >&2
    $VENV/bin/pip install --disable-pip-version-check -q "mypy==$MYPY" >>"$LOG" 2>&1 || {
        echo "tests/typecheck.sh: pip could not install mypy==$MYPY (details in $LOG)" >&2
        exit 1
    }
fi

# The settings, written afresh each run (a file of its own would be one more to keep in step).
CONFIG=$VENV/typecheck.ini
cat >"$CONFIG" <<'INI'
[mypy]
python_version = 3.11
platform = linux
check_untyped_defs = True
warn_unused_configs = True
cache_dir = .venv/mypy_cache

# boards/esp8266.py: MicroPython's os has dupterm(); CPython's has not.
[mypy-esp8266]
disable_error_code = attr-defined

# boards/rp2.py: its button() imports MicroPython's rp2 module, which this file's own name
# (rp2) hides here; on a board the file is board.py.
[mypy-rp2]
disable_error_code = attr-defined

# boards/unix.py: MicroPython's files take write(buf, off, n); CPython's take write(buf).
[mypy-unix]
disable_error_code = call-arg
INI

MYPYPATH=lib:boards:tests/stubs $VENV/bin/python -m mypy --config-file "$CONFIG" \
    examples/*.py boards/*.py
