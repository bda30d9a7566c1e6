#!/usr/bin/env python3
"""xwd2png.py IN.xwd OUT.png [X Y W H] - converts an X window dump (as Xvfb -fbdir keeps its
screen: 24-bit TrueColor, 32 bits a pixel) to a PNG, optionally cropped. Standard library only
(struct, zlib): the XWD header layout is X11's XWDFileHeader (25 big-endian CARD32 fields, then
the window name, then ncolors 12-byte colour entries, then the pixels)."""
import struct
import sys
import zlib


def main():
    if len(sys.argv) not in (3, 7):
        sys.exit("usage: xwd2png.py IN.xwd OUT.png [X Y W H]")
    data = open(sys.argv[1], "rb").read()
    h = struct.unpack(">25I", data[:100])
    header_size, version = h[0], h[1]
    if version != 7:
        sys.exit(f"xwd2png.py: {sys.argv[1]}: XWD version {version}, expected 7")
    width, height = h[4], h[5]
    byte_order, bits_per_pixel, bytes_per_line = h[7], h[11], h[12]
    red_mask, green_mask, blue_mask = h[14], h[15], h[16]
    ncolors = h[19]
    if bits_per_pixel != 32:
        sys.exit(f"xwd2png.py: {bits_per_pixel} bits a pixel, expected 32")
    pixels = data[header_size + 12 * ncolors:]
    x0, y0, w, hgt = 0, 0, width, height
    if len(sys.argv) == 7:
        x0, y0, w, hgt = (int(v) for v in sys.argv[3:7])
        w, hgt = min(w, width - x0), min(hgt, height - y0)

    def shift(mask):
        s = 0
        while mask and not mask & 1:
            mask >>= 1
            s += 1
        return s

    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    fmt = "<" if byte_order == 0 else ">"
    rows = []
    for y in range(y0, y0 + hgt):
        line = pixels[y * bytes_per_line + 4 * x0:y * bytes_per_line + 4 * (x0 + w)]
        words = struct.unpack(f"{fmt}{w}I", line)
        row = bytearray(b"\x00")
        for p in words:
            row += bytes(((p & red_mask) >> rs, (p & green_mask) >> gs, (p & blue_mask) >> bs))
        rows.append(bytes(row))

    def chunk(kind, body):
        c = struct.pack(">I", len(body)) + kind + body
        return c + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", w, hgt, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(b"".join(rows), 9))
    png += chunk(b"IEND", b"")
    open(sys.argv[2], "wb").write(png)


if __name__ == "__main__":
    main()
