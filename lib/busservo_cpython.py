# busservo_cpython: what busservo's modules use of MicroPython that CPython lacks, so that
# the same modules run on a computer (CPython 3.9 and later). Only CPython loads it: each
# module imports it where `import micropython` fails, which never happens on a board.
#
#   const(x)            x (MicroPython folds it in at compile time)
#   time                the time module, with ticks_ms/us/cpu, ticks_add, ticks_diff,
#                       sleep_ms and sleep_us as MicroPython has them
#   asyncio             the asyncio package, with sleep_ms, wait_for_ms, streams that
#                       have awrite()/aclose() (start_server, open_connection), and on
#                       CPython 3.9 a Lock that may be made before asyncio.run()
#   json                the json module, whose dumps() writes text as it is, as
#                       MicroPython's does (not as \u escapes)
#   bytearray8(n)       a bytearray that keeps the low 8 bits of what it is given
#   awaitable(cls)      makes `await obj` run obj.run(), as MicroPython's does
#   written(buf, ...)   what a UART's write(buf), write(buf, n) or write(buf, off, n) writes
#   UART                a base for a computer's port: read(), deinit() and `with`, made of its
#                       any(), readinto() and close()
#   BUSY_MS             what a busy computer may add to each of a USB link's hand-overs, ms:
#                       a computer's port counts it in its latency_ms (busservo_host's serial
#                       ports, busservo_hid's controllers)
#
# Ticks wrap at 2**30, as on a 32-bit board: ticks_diff() and ticks_add() are MicroPython's.
# json, and asyncio with what goes with it (async_sleep_ms, wait_for_ms, Stream,
# start_server, open_connection, Lock), are made on first use, by __getattr__ below:
# importing CPython's asyncio and json takes longer than the rest of a `busservo positions`
# command, which needs neither.
import sys as _sys
import time as _time
import types

BUSY_MS = 20
_PERIOD = 1 << 30
_MASK = _PERIOD - 1
_HALF = _PERIOD >> 1


def const(x):
    return x


class bytearray8(bytearray):
    """A bytearray that keeps the low 8 bits of an int stored in it, as MicroPython's
    does (CPython's raises ValueError): the driver stores 16-bit values' low bytes so."""

    __slots__ = ()

    def __setitem__(self, i, value):
        if type(value) is int:
            value &= 0xFF
        bytearray.__setitem__(self, i, value)


def _copy(module, name):
    # A module of the same name with all of module's attributes, to add to.
    new = types.ModuleType(name)
    new.__dict__.update((k, v) for k, v in module.__dict__.items() if k[:2] != "__")
    return new


def awaitable(cls):
    """cls's __await__ returns the coroutine of its run(), which MicroPython's await takes
    (a coroutine is a generator there); CPython's wants that coroutine's iterator."""

    def __await__(self):
        return self.run().__await__()

    cls.__await__ = cls.__iter__ = __await__
    return cls


# The stream protocol, as MicroPython's UART methods take it (the computer's ports: serial, HID).


def written(buf, off=None, nbytes=None):
    """The bytes that write(buf), write(buf, n) or write(buf, off, n) write: a memoryview of
    buf."""
    if nbytes is None:
        return memoryview(buf)[: off if off is not None else len(buf)]
    return memoryview(buf)[off : off + nbytes]


class UART:
    """What a computer's port (serial, HID) needs besides any(), readinto(), write() and
    close() to be used as MicroPython's machine.UART is: read(), deinit() and `with`."""

    def read(self, nbytes=-1):
        """bytes that have come (at most nbytes), or None when none has."""
        buf = bytearray(self.any() if nbytes < 0 else nbytes)
        got = self.readinto(buf) if buf else 0
        return bytes(buf[:got]) if got else None

    def deinit(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# time, with MicroPython's ticks.
time = _copy(_time, "time")
_ns = _time.monotonic_ns


def ticks_ms():
    return _ns() // 1000000 & _MASK


def ticks_us():
    return _ns() // 1000 & _MASK


def ticks_diff(end, start):
    return ((end - start + _HALF) & _MASK) - _HALF


def ticks_add(ticks, delta):
    if not -_HALF < delta < _HALF:
        raise OverflowError("ticks interval overflow")
    return (ticks + delta) & _MASK


def sleep_ms(ms):
    if ms > 0:
        _time.sleep(ms / 1000)


def sleep_us(us):
    if us > 0:
        _time.sleep(us / 1000000)


time.ticks_ms = ticks_ms
time.ticks_us = ticks_us
time.ticks_cpu = ticks_us
time.ticks_diff = ticks_diff
time.ticks_add = ticks_add
time.sleep_ms = sleep_ms
time.sleep_us = sleep_us


# Made when first asked for: `from busservo_cpython import asyncio` (or json) asks
# __getattr__ once, and the names are then the module's own.
def __getattr__(name):
    if name == "json":
        made = {"json": _make_json()}
    elif name in _ASYNCIO_NAMES:
        made = _make_asyncio()
    else:
        raise AttributeError("module 'busservo_cpython' has no attribute %r" % name)
    globals().update(made)
    return made[name]


# json, whose dumps() writes "é" as MicroPython's does, not "\u00e9".
def _make_json():
    import json as _json

    json = _copy(_json, "json")
    json.dumps = lambda obj: _json.dumps(obj, ensure_ascii=False)
    return json


# asyncio, with MicroPython's additions.
_ASYNCIO_NAMES = (
    "asyncio",
    "async_sleep_ms",
    "wait_for_ms",
    "Stream",
    "start_server",
    "open_connection",
    "Lock",
)


def _make_asyncio():
    import asyncio as _asyncio

    asyncio = _copy(_asyncio, "asyncio")

    async def async_sleep_ms(ms):
        await _asyncio.sleep(max(ms, 0) / 1000)

    async def wait_for_ms(aw, ms):
        return await _asyncio.wait_for(aw, ms / 1000)

    class Stream:
        """A connection's reader and writer in one, as MicroPython's asyncio gives it (to
        both arguments of a start_server() callback): read, readline, readexactly, write
        then drain, awrite, close then wait_closed, aclose."""

        def __init__(self, reader, writer):
            self._reader = reader
            self._writer = writer

        def get_extra_info(self, name, default=None):
            return self._writer.get_extra_info(name, default)

        async def read(self, n=-1):
            return await self._reader.read(n)

        async def readline(self):
            return await self._reader.readline()

        async def readexactly(self, n):
            return await self._reader.readexactly(n)

        def write(self, data):
            self._writer.write(data)

        async def drain(self):
            await self._writer.drain()

        async def awrite(self, data, off=0, sz=-1):
            if off or sz != -1:
                data = memoryview(data)[off : None if sz == -1 else off + sz]
            self._writer.write(data)
            await self._writer.drain()

        def close(self):
            self._writer.close()

        async def wait_closed(self):
            try:
                await self._writer.wait_closed()
            except (OSError, _asyncio.CancelledError):
                pass  # the peer reset it: closed all the same

        async def aclose(self):
            self.close()
            await self.wait_closed()

    _start_server = _asyncio.start_server
    _open_connection = _asyncio.open_connection

    async def start_server(callback, host, port, backlog=5, ssl=None):
        def each(reader, writer):
            stream = Stream(reader, writer)
            return callback(stream, stream)

        return await _start_server(each, host, port, backlog=backlog, ssl=ssl)

    async def open_connection(host, port, ssl=None):
        reader, writer = await _open_connection(host, port, ssl=ssl)
        stream = Stream(reader, writer)
        return stream, stream

    asyncio.sleep_ms = async_sleep_ms
    asyncio.wait_for_ms = wait_for_ms
    asyncio.start_server = start_server
    asyncio.open_connection = open_connection

    _Lock = _asyncio.Lock

    class Lock:
        """asyncio.Lock, made in the loop that first uses it. CPython 3.9's binds to the loop
        current when it is made, and a driver made before asyncio.run() has none (3.10 and
        later bind on first use, as this does)."""

        def __init__(self):
            self._lock = None

        def _made(self):
            if self._lock is None:
                self._lock = _Lock()
            return self._lock

        def locked(self):
            return self._lock is not None and self._lock.locked()

        async def acquire(self):
            return await self._made().acquire()

        def release(self):
            self._made().release()

        async def __aenter__(self):
            await self.acquire()

        async def __aexit__(self, *exc):
            self.release()

    if _sys.version_info < (3, 10):
        asyncio.Lock = Lock
    made = dict(locals())
    return {name: made[name] for name in _ASYNCIO_NAMES}
