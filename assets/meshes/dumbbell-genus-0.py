"""Writes dumbbell-genus-0.obj: two balls joined by a neck, a genus-0 mesh for `ntori fit`.

An icosphere (the icosahedron split three times, 642 vertices, 1280 triangles) whose points
(x, y, z) on the unit sphere move to (1.8x, ry, rz) with r = 0.45 + 0.55|x|^1.5: 3.6 units long,
1 unit across at the balls, 0.45 at the neck. Run: python3 dumbbell-genus-0.py > dumbbell-genus-0.obj
"""
import math

t = (1 + 5 ** 0.5) / 2
points = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
          (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
points = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in points]
faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
for _ in range(3):
    middle = {}

    def mid(a, b):
        key = (min(a, b), max(a, b))
        if key not in middle:
            p = [(points[a][i] + points[b][i]) / 2 for i in range(3)]
            n = math.sqrt(sum(x * x for x in p))
            points.append(tuple(x / n for x in p))
            middle[key] = len(points) - 1
        return middle[key]

    split = []
    for a, b, c in faces:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    faces = split

print("# ntori example mesh: a dumbbell, two balls joined by a neck (genus 0), 3.6 units long")
print("# made by assets/meshes/dumbbell-genus-0.py; License: CC0 1.0")
for x, y, z in points:
    r = 0.45 + 0.55 * abs(x) ** 1.5
    print("v %.6f %.6f %.6f" % (1.8 * x, r * y, r * z))
for f in faces:
    print("f %d %d %d" % tuple(i + 1 for i in f))
