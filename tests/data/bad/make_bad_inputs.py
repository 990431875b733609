#!/usr/bin/env python3
"""Writes the bad-input corpus of tests/data/bad (one small file per failure class; the table
in tests/apps/bad_input_test.cpp says what the CLI must answer to each). Deterministic: running
it again gives the same bytes. The .dbf6/.forest/.tlobe files are damaged copies of the fuzz
seeds (fuzz/seeds), with their CRC-32 recomputed so the damage reaches the parser.

Usage: python3 tests/data/bad/make_bad_inputs.py   (from the repository root or anywhere)
"""
import math
import os
import random
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = os.path.join(HERE, "..", "..", "..", "fuzz", "seeds")


def write(name, data):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def las(points, scale=0.001, count=None, magic=b"LASF"):
    """LAS 1.2, point format 0: 227-byte header, 20-byte records."""
    count = len(points) if count is None else count
    xs = [p[0] for p in points] or [0.0]
    ys = [p[1] for p in points] or [0.0]
    zs = [p[2] for p in points] or [0.0]
    h = bytearray(227)
    h[0:4] = magic
    h[24], h[25] = 1, 2
    h[26:26 + 9] = b"treelobes"
    struct.pack_into("<HHHIIBHI", h, 90, 1, 2024, 227, 227, 0, 0, 20, count)
    struct.pack_into("<5I", h, 111, count, 0, 0, 0, 0)
    struct.pack_into("<3d3d", h, 131, scale, scale, scale, 0.0, 0.0, 0.0)
    struct.pack_into("<6d", h, 179, max(xs), min(xs), max(ys), min(ys), max(zs), min(zs))
    body = b"".join(struct.pack("<3iHBBbBH", *(int(round(c / scale)) for c in p), 100, 0x09, 1, 0, 0, 1) for p in points)
    return bytes(h) + body


def xyz(points):
    return "".join("%.4f %.4f %.4f\n" % p for p in points)


def skeleton_ply(vertices, edges):
    head = ["ply", "format ascii 1.0", "element vertex %d" % len(vertices), "property float x", "property float y",
            "property float z", "property float radius", "element edge %d" % len(edges), "property int vertex1",
            "property int vertex2", "end_header"]
    return "\n".join(head + ["%g %g %g %g" % v for v in vertices] + ["%d %d" % e for e in edges]) + "\n"


def with_crc(body):
    return body + struct.pack("<I", zlib.crc32(body))


def seed(target, name):
    with open(os.path.join(SEEDS, target, name), "rb") as f:
        return f.read()


def stem_points(n, rng):
    """A 3 m vertical stem of radius 0.1 m."""
    pts = []
    for i in range(n):
        a = rng.uniform(0, 2 * math.pi)
        pts.append((0.1 * math.cos(a), 0.1 * math.sin(a), rng.uniform(0, 3)))
    return pts


def house(rng):
    """Four 6 x 4 m walls and a gable roof: planar, no stem."""
    pts = []
    for _ in range(3000):
        side = rng.randrange(6)
        u, v = rng.uniform(0, 1), rng.uniform(0, 1)
        if side == 0: pts.append((6 * u, 0.0, 3 * v))
        elif side == 1: pts.append((6 * u, 4.0, 3 * v))
        elif side == 2: pts.append((0.0, 4 * u, 3 * v))
        elif side == 3: pts.append((6.0, 4 * u, 3 * v))
        else:  # the two roof planes rise from the long walls to a ridge at y = 2, z = 5
            y = 2 * v if side == 4 else 4 - 2 * v
            pts.append((6 * u, y, 3 + 2 * min(y, 4 - y) / 2))
    return pts


def main():
    rng = random.Random(23)
    stem = stem_points(200, rng)
    whole = las(stem)
    write("truncated.las", whole[:227 + 20 * 120 + 7])
    write("wrong_magic.las", las(stem, magic=b"LASX"))
    write("count_exceeds_file.las", las(stem, count=1_000_000))
    write("absurd_scale.las", las([(0, 0, 0)] * 3, scale=1e300))
    write("empty_tile.las", las([]))
    write("count_overflow.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 18446744073709551615\n"
          "property float x\nproperty float y\nproperty float z\nend_header\n" + "\0" * 24)
    write("negative_count.ply", "ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\nproperty float y\n"
          "property float z\nend_header\n0 0 0\n")
    write("nan.xyz", "nan nan nan\n" * 50)
    write("inf.xyz", "".join("%d inf 1\n" % i for i in range(50)))
    write("two_points.xyz", xyz([(0, 0, 0), (0, 0, 1)]))
    write("identical_points.xyz", xyz([(1.5, 2.5, 3.5)] * 500))
    write("house.xyz", xyz(house(rng)))
    write("skeleton_cycle.ply", skeleton_ply([(0, 0, 0, .1), (0, 0, 1, .1), (0, 1, 1, .1), (1, 0, 2, .1)],
                                             [(0, 1), (1, 2), (2, 0)]))
    write("skeleton_two_roots.ply", skeleton_ply([(0, 0, 0, .1), (0, 0, 1, .1), (0, 0, 2, .1), (5, 0, 0, .1), (5, 0, 1, .1)],
                                                 [(0, 1), (1, 2), (3, 4)]))
    # A fork (6) whose lateral never comes: the code ends with the fork still queued.
    write("unbalanced_forks.code", "2228222622282227\n9,8,7,6\n")

    dbf6 = seed("dbf6", "birch_best.dbf6")
    write("truncated.dbf6", dbf6[: len(dbf6) // 2])
    write("wrong_magic.dbf6", b"DBF7" + dbf6[4:])
    forest = bytearray(seed("forest", "three_best.forest"))
    index_size = struct.unpack_from("<I", forest, 9)[0]
    struct.pack_into("<I", forest, 5, 0xFFFFFFFF)  # tree count
    write("absurd_count.forest", with_crc(bytes(forest[: 37 + index_size])) + bytes(forest[37 + index_size + 4:]))
    tlobe = bytearray(seed("tlobe", "lagerstroemia.tlobe"))
    struct.pack_into("<I", tlobe, 8, 0x3FFFFFFF)  # inflated payload size: 1 GiB from a few kB
    crc = zlib.crc32(bytes(tlobe[20:]), zlib.crc32(bytes(tlobe[:16])))
    struct.pack_into("<I", tlobe, 16, crc)
    write("absurd_size.tlobe", bytes(tlobe))


if __name__ == "__main__":
    main()
