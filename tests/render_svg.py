# CPython, not MicroPython: render an SVG to PNG with resvg (the resvg-py wheel that tests/run.sh
# installs into .venv/), then read the PNG back and say what is in it, for tests/test_docs.py:
#
#   .venv/bin/python tests/render_svg.py IN.svg OUT.png
#
# prints "WIDTHxHEIGHT colours=N ink=P": the picture's size, how many colours it has, and the
# share of its pixels (in %) that differ from its top-left corner's (the background). Exit status
# 3 if no renderer can be imported (the test then skips), 1 on any other error.
import struct
import sys
import zlib


def pixels(png):
    """The PNG's width, height and rows of RGBA bytes (8-bit RGBA, as resvg writes)."""
    if png[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat = 8, b""
    while pos < len(png):
        (length,) = struct.unpack(">I", png[pos : pos + 4])
        kind, body = png[pos + 4 : pos + 8], png[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            if (depth, colour) != (8, 6):
                raise ValueError("not 8-bit RGBA: depth %d, colour type %d" % (depth, colour))
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * 4, [], bytearray(width * 4)
    for y in range(height):
        start = y * (stride + 1)
        kind, row = raw[start], bytearray(raw[start + 1 : start + 1 + stride])
        for i in range(stride):  # undo the row's filter (PNG spec, section 9)
            a = row[i - 4] if i >= 4 else 0
            b = prev[i]
            c = prev[i - 4] if i >= 4 else 0
            if kind == 1:
                row[i] = (row[i] + a) & 255
            elif kind == 2:
                row[i] = (row[i] + b) & 255
            elif kind == 3:
                row[i] = (row[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(row)
        prev = row
    return width, height, rows


def main(svg, out):
    try:
        import resvg_py
    except ImportError as e:
        print("no renderer: %s" % e)
        return 3
    png = bytes(resvg_py.svg_to_bytes(svg_path=svg))
    with open(out, "wb") as f:
        f.write(png)
    width, height, rows = pixels(png)
    background = bytes(rows[0][:4])
    colours, ink = set(), 0
    for row in rows:
        for x in range(0, len(row), 4):
            pixel = bytes(row[x : x + 4])
            colours.add(pixel)
            ink += pixel != background
    print("%dx%d colours=%d ink=%.1f" % (width, height, len(colours), 100 * ink / width / height))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
