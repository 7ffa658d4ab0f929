"""Writes gear-genus-1.obj: a gear as CAD programs tessellate one, a genus-1 mesh for `ntori fit`.

A prism 0.8 high over an annulus whose outer rim is r(θ) = 1 + 0.12 cos 10θ (ten rounded teeth)
and inner rim 0.45, with vertices only on its four rims (120 on each): the faces are spanned by
long thin triangles, each wall triangle a needle from the top rim to the bottom one, and the rims
are sharp. `ntori fit` splits the long edges before it fits (see README).
Run: python3 gear-genus-1.py > gear-genus-1.obj
"""
import math

n, teeth, height = 120, 10, 0.8


def rim(k, outer, z):
    theta = 2 * math.pi * (k % n) / n
    r = 1 + 0.12 * math.cos(teeth * theta) if outer else 0.45
    return (r * math.cos(theta), r * math.sin(theta), z)


rings = [(True, height), (False, height), (True, 0.0), (False, 0.0)]
points = [rim(k, outer, z) for outer, z in rings for k in range(n)]
TOP_OUT, TOP_IN, BOTTOM_OUT, BOTTOM_IN = range(4)


def index(ring, k):
    return ring * n + k % n


faces = []
for k in range(n):
    # Top (+z), bottom (-z), outer wall (outwards), inner wall (towards the axis).
    for quad in [[(TOP_OUT, k), (TOP_OUT, k + 1), (TOP_IN, k + 1), (TOP_IN, k)],
                 [(BOTTOM_OUT, k), (BOTTOM_IN, k), (BOTTOM_IN, k + 1), (BOTTOM_OUT, k + 1)],
                 [(TOP_OUT, k), (BOTTOM_OUT, k), (BOTTOM_OUT, k + 1), (TOP_OUT, k + 1)],
                 [(TOP_IN, k), (TOP_IN, k + 1), (BOTTOM_IN, k + 1), (BOTTOM_IN, k)]]:
        a, b, c, d = (index(*v) for v in quad)
        faces += [(a, b, c), (a, c, d)]

print("# gear-genus-1.obj: made by gear-genus-1.py (CC0 1.0)")
for p in points:
    print("v %.6f %.6f %.6f" % p)
for f in faces:
    print("f %d %d %d" % tuple(v + 1 for v in f))
