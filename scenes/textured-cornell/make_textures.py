"""Writes checker.png (64 x 64: 8 x 8 squares of warm white and slate, 8-bit sRGB) and
poster.ppm (128 x 128: a colour grid with a white border), which
`convert poster.ppm -quality 90 poster.jpg` (ImageMagick) turns into the JPEG. Ours, CC0."""
import struct
import zlib


def png(path, width, height, pixel):
    rows = b"".join(
        b"\x00" + bytes(c for x in range(width) for c in pixel(x, y)) for y in range(height)
    )

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows, 9)))
        f.write(chunk(b"IEND", b""))


def checker(x, y):
    return (230, 220, 200) if (x // 8 + y // 8) % 2 == 0 else (60, 70, 90)


def poster(x, y):
    if min(x, y, 127 - x, 127 - y) < 8:
        return (240, 240, 240)
    i, j = (x - 8) // 28, (y - 8) // 28
    palette = [(200, 40, 40), (40, 160, 60), (40, 80, 200), (220, 180, 40)]
    return palette[(i + 2 * j) % 4]


png("checker.png", 64, 64, checker)
with open("poster.ppm", "wb") as f:
    f.write(b"P6 128 128 255\n")
    f.write(bytes(c for y in range(128) for x in range(128) for c in poster(x, y)))
