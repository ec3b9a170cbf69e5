"""Reads a GSD file written by the Rust crate with gsd.hoomd and checks it against expected values.

Usage: python3 read_rust.py TRAJECTORY.gsd EXPECTED.json

EXPECTED.json holds, per frame, the step, N, the bit patterns of the f32 positions and
orientations (uint32) and of the f64 log/time (uint64), the type ids, the type names and the
type shapes (JSON objects). Floats are compared bit for bit. Exits non-zero with a message on
the first mismatch.
"""

import json
import sys

import gsd.hoomd
import numpy


def check(what, got, expected):
    if not numpy.array_equal(numpy.asarray(got), numpy.asarray(expected)):
        sys.exit(f'{what}: read {got!r}, expected {expected!r}')


def main(path, expected_path):
    with open(expected_path) as f:
        expected = json.load(f)
    with gsd.hoomd.open(path, mode='r') as traj:
        check('number of frames', len(traj), len(expected['frames']))
        check('schema', traj.file.schema, 'hoomd')
        check('application', traj.file.application, expected['application'])
        for k, e in enumerate(expected['frames']):
            frame = traj[k]
            p = frame.particles
            check(f'frame {k} step', frame.configuration.step, e['step'])
            check(f'frame {k} N', p.N, e['N'])
            check(
                f'frame {k} box bits',
                frame.configuration.box.astype(numpy.float32).view(numpy.uint32),
                e['box_bits'],
            )
            check(f'frame {k} position dtype', str(p.position.dtype), 'float32')
            check(
                f'frame {k} position bits',
                p.position.view(numpy.uint32).reshape(-1),
                e['position_bits'],
            )
            check(
                f'frame {k} orientation bits',
                p.orientation.view(numpy.uint32).reshape(-1),
                e['orientation_bits'],
            )
            check(f'frame {k} typeid', p.typeid, e['typeid'])
            check(f'frame {k} types', list(p.types), e['types'])
            if p.type_shapes != e['type_shapes']:
                sys.exit(f'frame {k} type_shapes: read {p.type_shapes}, expected {e["type_shapes"]}')
            time = frame.log['time']
            check(f'frame {k} log/time dtype', str(time.dtype), 'float64')
            check(f'frame {k} log/time bits', time.view(numpy.uint64), [e['time_bits']])
    print(f'ok: {len(expected["frames"])} frames read by gsd.hoomd')


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
