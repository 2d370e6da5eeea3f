#!/usr/bin/env python3
"""A wavy grid of about 10 million triangles (2237 x 2237 vertices), as an
OBJ and as a binary little-endian PLY of the same vertices and faces: the
meshes the loading benchmarks open (BENCHMARKS.md).

Usage: scripts/big-grid.py [FOLDER]   (writes grid10m.obj and grid10m.ply)
"""
import math
import os
import struct
import sys

N = 2237  # vertices per side: 2 * (N - 1)^2 = 9,999,392 triangles


def height(i, y):
    return 0.05 * math.sin(13 * i / N) * math.cos(11 * y)


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else "."
    with open(os.path.join(folder, "grid10m.obj"), "w", buffering=1 << 24) as out:
        for j in range(N):
            y = j / (N - 1)
            out.write("".join("v %.6f %.6f %.6f\n" % (i / (N - 1), y, height(i, y)) for i in range(N)))
        for j in range(N - 1):
            rows = []
            for i in range(N - 1):
                a = j * N + i + 1
                b, c = a + 1, a + N
                d = c + 1
                rows.append("f %d %d %d\nf %d %d %d\n" % (a, b, d, a, d, c))
            out.write("".join(rows))
    with open(os.path.join(folder, "grid10m.ply"), "wb") as out:
        faces = 2 * (N - 1) ** 2
        out.write(
            b"ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
            b"property float x\nproperty float y\nproperty float z\n"
            b"element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (N * N, faces)
        )
        for j in range(N):
            y = j / (N - 1)
            out.write(b"".join(struct.pack("<fff", i / (N - 1), y, height(i, y)) for i in range(N)))
        for j in range(N - 1):
            rows = []
            for i in range(N - 1):
                a = j * N + i
                b, c = a + 1, a + N
                d = c + 1
                rows.append(struct.pack("<BiiiBiii", 3, a, b, d, 3, a, d, c))
            out.write(b"".join(rows))


if __name__ == "__main__":
    main()
