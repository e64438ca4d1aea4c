#!/usr/bin/env python3
"""Writes the textures and the card mesh of scenes/textured.toml and the sky
of scenes/environment.toml (Python's standard library only): a brick albedo
and its tangent-space normal map, a leaf with an alpha mask, a unit square
with texture coordinates, and a latitude-longitude HDR sky with a sun.

Normal-map convention (caustic's, Mitsuba's and glTF's): red along +u,
green toward the image's top, blue out of the surface; 8-bit values encode
n = 2 * value / 255 - 1.
"""
import math
import os
import random
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "scenes", "textures")
MESHES = os.path.join(HERE, "..", "scenes", "meshes")


def write_png(path, width, height, rows, channels):
    """rows: list of bytes objects, one per row, top row first."""
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    colour_type = {3: 2, 4: 6}[channels]

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9))
    png += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def brick_height(x, y):
    """Height in [0, 1] at texel (x, y) of a 256-texel tile: 4 courses of 2
    bricks, alternate courses offset by half a brick; mortar grooves."""
    course = int(y // 64)
    bx = (x + (64 if course % 2 else 0)) % 128
    by = y % 64
    d = min(bx, 128 - bx, by, 64 - by)  # distance to the nearest joint
    return max(0.0, min(1.0, (d - 3.0) / 4.0))


def bricks(size=256):
    rng = random.Random(7)
    tone = {}
    rows, heights = [], [[brick_height(x, y) for x in range(size)] for y in range(size)]
    for y in range(size):
        row = []
        for x in range(size):
            course = y // 64
            key = (course, ((x + (64 if course % 2 else 0)) % 256) // 128)
            if key not in tone:
                tone[key] = 0.75 + 0.25 * rng.random()
            h = heights[y][x]
            grain = 0.9 + 0.1 * rng.random()
            if h <= 0.0:
                c = (150, 145, 135)  # mortar
                c = tuple(int(v * grain) for v in c)
            else:
                t = tone[key] * grain
                c = (int(168 * t), int(74 * t), int(52 * t))
            row += c
        rows.append(row)
    write_png(os.path.join(OUT, "bricks.png"), size, size, rows, 3)
    # Normal map from the height field: n = (-dh/du, -dh/dv_up, 1/strength).
    strength = 4.0
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            dx = heights[y][(x + 1) % size] - heights[y][(x - 1) % size]
            # The image's up is toward smaller y.
            dy_up = heights[(y - 1) % size][x] - heights[(y + 1) % size][x]
            n = (-dx * strength, -dy_up * strength, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            row += [int(round((c / length * 0.5 + 0.5) * 255)) for c in n]
        rows.append(row)
    write_png(os.path.join(OUT, "bricks-normal.png"), size, size, rows, 3)


def leaf(size=128):
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            # A leaf along the diagonal: an ellipse in rotated coordinates, a stem.
            u, v = (x + 0.5) / size - 0.5, (y + 0.5) / size - 0.5
            a, b = (u + v) / math.sqrt(2), (u - v) / math.sqrt(2)
            inside = (a / 0.42) ** 2 + (b / 0.2) ** 2 <= 1.0
            stem = abs(b) < 0.012 and -0.5 < a < 0.0
            vein = abs(b) < 0.01 and inside
            g = 0.55 + 0.3 * (1 - abs(b) / 0.2) if inside else 0.4
            c = (int(60 * g), int(150 * g), int(40 * g))
            if vein or stem:
                c = (150, 170, 70)
            row += c + ((255,) if inside or stem else (0,))
        rows.append(row)
    write_png(os.path.join(OUT, "leaf.png"), size, size, rows, 4)


def write_hdr(path, width, height, pixel):
    """A Radiance RGBE file (flat scanlines), top row first; pixel(x, y) -> (r, g, b)."""
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
    out += f"-Y {height} +X {width}\n".encode()
    for y in range(height):
        for x in range(width):
            rgb = pixel(x, y)
            m = max(rgb)
            if m < 1e-32:
                out += bytes(4)
                continue
            mantissa, exponent = math.frexp(m)
            scale = mantissa * 256.0 / m
            out += bytes([int(c * scale) for c in rgb] + [exponent + 128])
    with open(path, "wb") as f:
        f.write(out)


def sky(width=256, height=128):
    """Blue sky brighter toward the horizon, a sun 30° above it (2° wide, a
    few thousand times the sky), and a grey-brown ground."""
    sun_theta, sun_phi = math.radians(60.0), math.radians(40.0)
    sun = (math.sin(sun_theta) * math.sin(sun_phi), math.cos(sun_theta), -math.sin(sun_theta) * math.cos(sun_phi))
    cos_sun = math.cos(math.radians(1.0))

    def pixel(x, y):
        theta = math.pi * (y + 0.5) / height
        phi = 2.0 * math.pi * (x + 0.5) / width
        d = (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))
        if sum(a * b for a, b in zip(d, sun)) > cos_sun:
            return (4000.0, 3600.0, 3000.0)
        if d[1] < 0.0:
            return (0.12, 0.1, 0.08)
        t = d[1] ** 0.5
        return (0.9 - 0.6 * t, 1.0 - 0.5 * t, 1.2 - 0.1 * t)

    write_hdr(os.path.join(OUT, "sky.hdr"), width, height, pixel)


def card():
    # A unit square in the xy plane facing +z, OBJ texture coordinates (v up).
    text = (
        "# A unit square facing +z with texture coordinates (scenes/textured.toml).\n"
        "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
    )
    with open(os.path.join(MESHES, "card.obj"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    bricks()
    leaf()
    card()
    sky()
