# The test modules on CPython (3.9 and later), the same source as on the unix port:
#
#   .venv/bin/python tests/cpython.py test_frames      # one module, from the repository's root
#
# What the tests use of MicroPython and CPython lacks comes from here, once, before the
# module is imported: time's ticks and sleep_ms/us, asyncio's sleep_ms, wait_for_ms and
# streams with awrite() (lib/busservo_cpython.py's, put into the standard modules: in this
# test process only, so that a test's own `import time` has them as the driver's does), and
# deflate's DeflateIO (gzip's) for reading the panel's page.
# What cannot apply is skipped where it is measured (heap bytes per call: CPython has no
# gc.mem_alloc()). Prints each test's line as micropython-unittest does ("NAME (CLASS) ...
# ok"), and last tests/run.sh's counts line. RUN_SH_K runs the tests whose name (or class's
# name) holds it, as in tests/run.sh.
import asyncio
import gzip
import os
import sys
import time
import traceback
import types
import unittest

sys.path[:0] = ["tests", "lib", "boards"]

import busservo_cpython  # noqa: E402

for _name in (
    "ticks_ms",
    "ticks_us",
    "ticks_cpu",
    "ticks_diff",
    "ticks_add",
    "sleep_ms",
    "sleep_us",
):
    setattr(time, _name, getattr(busservo_cpython.time, _name))
asyncio.sleep_ms = busservo_cpython.async_sleep_ms
asyncio.wait_for_ms = busservo_cpython.wait_for_ms
asyncio.start_server = busservo_cpython.start_server
asyncio.open_connection = busservo_cpython.open_connection
asyncio.Lock = busservo_cpython.asyncio.Lock  # on 3.9, one that binds to a loop on first use

# MicroPython's deflate module, for what the tests read of the gzipped page.
deflate = types.ModuleType("deflate")
deflate.GZIP = 3
deflate.DeflateIO = lambda stream, kind=0: gzip.GzipFile(fileobj=stream)
sys.modules["deflate"] = deflate

COUNTS = "tests/run.sh-counts:"


class Result(unittest.TestResult):
    # micropython-unittest's lines: "NAME (CLASS) ... ok", " FAIL", " skipped: WHY".
    def startTest(self, test):
        super().startTest(test)
        print("%s (%s) ..." % (test._testMethodName, type(test).__qualname__), end="", flush=True)

    def addSuccess(self, test):
        super().addSuccess(test)
        print(" ok", flush=True)

    def addSkip(self, test, reason):
        super().addSkip(test, reason)
        print(" skipped:", reason, flush=True)

    def addFailure(self, test, err):
        super().addFailure(test, err)
        print(" FAIL", flush=True)

    def addError(self, test, err):
        super().addError(test, err)
        print(" FAIL", flush=True)


def main(name):
    module = __import__(name)
    suite = unittest.defaultTestLoader.loadTestsFromModule(module)
    k = os.getenv("RUN_SH_K")
    if k:
        picked = unittest.TestSuite()
        for test in _tests(suite):
            if k in test._testMethodName or k in type(test).__name__:
                picked.addTest(test)
        suite = picked
    result = Result()
    suite.run(result)
    print("Ran %d tests\n" % result.testsRun)
    bad = result.failures + result.errors
    if bad:
        print("FAILED (failures=%d, errors=%d)" % (len(result.failures), len(result.errors)))
        for test, text in bad:
            print("-" * 70)
            print("%s (%s)" % (test._testMethodName, type(test).__qualname__))
            print(text)
    else:
        print("OK" + (" (%d skipped)" % len(result.skipped) if result.skipped else ""))
    print(COUNTS, result.testsRun, len(bad), len(result.skipped), flush=True)
    return not bad


def _tests(suite):
    for test in suite:
        if isinstance(test, unittest.TestSuite):
            yield from _tests(test)
        else:
            yield test


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python tests/cpython.py test_MODULE")
    try:
        sys.exit(0 if main(sys.argv[1]) else 1)
    except Exception:
        traceback.print_exc()
        sys.exit(1)
