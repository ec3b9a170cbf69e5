"""Writes the GSD start files of the bad-scene corpus (run from this folder; needs `gsd`)."""

import gsd.hoomd
import numpy

POSITIONS = [[1.0, 1.0, 1.0], [1.0, -1.0, 1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, -1.0]]


def frame(types=("A",), box=(6, 6, 6, 0, 0, 0), velocity=True, orientation=False,
          angmom=False, mass=None, step=0):
    f = gsd.hoomd.Frame()
    f.configuration.step = step
    f.configuration.box = list(box)
    f.particles.N = 4
    f.particles.types = list(types)
    f.particles.typeid = [len(types) - 1] * 4
    f.particles.position = numpy.array(POSITIONS, dtype=numpy.float32)
    if velocity:
        f.particles.velocity = numpy.full((4, 3), 0.1, dtype=numpy.float32)
    if orientation:
        f.particles.orientation = numpy.array([[1, 0, 0, 0]] * 4, dtype=numpy.float32)
    if angmom:
        f.particles.angmom = numpy.array([[0, 0.01, 0, 0]] * 4, dtype=numpy.float32)
    if mass is not None:
        f.particles.mass = numpy.full(4, mass, dtype=numpy.float32)
    return f


def write(name, *frames):
    with gsd.hoomd.open(name, "w") as t:
        for f in frames:
            t.append(f)


write("start-spheres.gsd", frame(), frame(step=1))
write("start-other-type.gsd", frame(types=("A", "B")))
write("start-no-velocity.gsd", frame(velocity=False))
write("start-heavier.gsd", frame(mass=2.0))
write("start-tilted.gsd", frame(box=(6, 6, 6, 0.5, 0, 0)))
write("start-rods-no-angmom.gsd", frame(types=("rod",), orientation=True))
