"""Writes a GSD file with gsd.hoomd for the Rust reader to check.

Usage: python3 write_python.py TRAJECTORY.gsd

Three frames of N = 4 particles of types "A" and "B" (shapes: a sphere of diameter 1.0 and a
convex polyhedron), box 8 x 9 x 10 (length units); in frame k particle i is at
(0.5 i + k, -0.25 i, 1 + i), orientations are (1, 0, 0, 0) except particle 1's (0, 1, 0, 0),
log/time = 0.125 k (float64), step 1000 k. gsd.hoomd leaves out of frames 1 and 2 what equals
frame 0 (types, type ids, shapes, orientations, box), so the reader's frame-0 fallback is
exercised. All values are exact in float32.
"""

import sys

import gsd.hoomd
import numpy

N = 4


def frame(k):
    f = gsd.hoomd.Frame()
    f.configuration.step = 1000 * k
    f.configuration.box = [8, 9, 10, 0, 0, 0]
    f.particles.N = N
    f.particles.types = ['A', 'B']
    f.particles.typeid = [0, 1, 0, 1]
    f.particles.type_shapes = [
        {'type': 'Sphere', 'diameter': 1.0},
        {
            'type': 'ConvexPolyhedron',
            'rounding_radius': 0.125,
            'vertices': [[0.5, 0.5, 0.5], [0.5, -0.5, -0.5], [-0.5, 0.5, -0.5], [-0.5, -0.5, 0.5]],
        },
    ]
    f.particles.position = numpy.array(
        [[0.5 * i + k, -0.25 * i, 1.0 + i] for i in range(N)], dtype=numpy.float32
    )
    q = numpy.zeros((N, 4), dtype=numpy.float32)
    q[:, 0] = 1
    q[1] = [0, 1, 0, 0]
    f.particles.orientation = q
    f.log['time'] = numpy.array([0.125 * k], dtype=numpy.float64)
    return f


def main(path):
    with gsd.hoomd.open(path, mode='w') as traj:
        for k in range(3):
            traj.append(frame(k))
    print(f'ok: wrote {path}')


if __name__ == '__main__':
    main(sys.argv[1])
