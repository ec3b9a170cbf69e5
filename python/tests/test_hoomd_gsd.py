"""Starting dmd from GSD files laid out as HOOMD-blue's `hoomd.write.GSD` writes them.

HOOMD-blue itself is not on PyPI (it is distributed through conda-forge and built from source),
so these files are written with the `gsd` package's low-level API (`gsd.fl`) chunk by chunk in
HOOMD's layout: the hoomd schema, frame 0 holding every chunk whose value is not the schema's
default (`particles/types`, `particles/mass`, `particles/moment_inertia`, `particles/velocity`,
`particles/angmom`, `particles/image`, ...; `particles/typeid` left out when every particle has
type 0), and later frames only the categories written every frame (HOOMD's `dynamic`, by default
`["property"]`: `configuration/step`, `configuration/box`, `particles/N`, `particles/position`,
`particles/orientation`). A reader takes a chunk that a later frame lacks from frame 0.
"""

from pathlib import Path

import numpy as np
import pytest

import dmdsim

fl = pytest.importorskip("gsd.fl", reason="the gsd package is not installed")

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def types_chunk(names):
    """`particles/types` as HOOMD stores it: one NUL-padded row of int8 per type name."""
    width = max(len(n) for n in names) + 1
    rows = np.zeros((len(names), width), dtype=np.int8)
    for k, n in enumerate(names):
        rows[k, : len(n)] = np.frombuffer(n.encode(), dtype=np.int8)
    return rows


def write_hoomd_gsd(path, frames):
    """A GSD file of the hoomd schema (1.4, HOOMD-blue 4's) whose frames hold the chunks given,
    each frame a dict {chunk name: array}."""
    with fl.open(
        name=str(path),
        mode="w",
        application="HOOMD-blue v4.9.0",
        schema="hoomd",
        schema_version=[1, 4],
    ) as f:
        for chunks in frames:
            for name, data in chunks.items():
                f.write_chunk(name=name, data=np.ascontiguousarray(data))
            f.end_frame()


def box_chunk(length, tilts=(0.0, 0.0, 0.0)):
    return np.array([length, length, length, *tilts], dtype=np.float32)


def lattice(per_side, length):
    """Simple cubic sites in HOOMD's centred box [-L/2, L/2)."""
    a = length / per_side
    k = np.arange(per_side)
    grid = np.stack(np.meshgrid(k, k, k, indexing="ij"), axis=-1).reshape(-1, 3)
    return ((grid + 0.5) * a - length / 2).astype(np.float32)


def wrap(x, length):
    return (x + length / 2) % length - length / 2


def same_point(a, b, box):
    """The largest distance between rows of `a` and `b` across periodic images."""
    d = a - b
    d -= box * np.round(d / box)
    return np.abs(d).max()


def qmul(a, b):
    """Products of quaternions (w, x, y, z), row by row."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=1,
    )


def rotate(q, v):
    """v rotated by the unit quaternions q (body → lab), row by row."""
    p = np.concatenate([np.zeros((len(v), 1)), v], axis=1)
    conj = q * np.array([1.0, -1.0, -1.0, -1.0])
    return qmul(qmul(q, p), conj)[:, 1:]


def random_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    return q


# ---- spheres -----------------------------------------------------------------------------------

N_SIDE = 5
N_SPHERES = N_SIDE**3
RHO = 0.5
L_SPHERES = float(np.float32((N_SPHERES / RHO) ** (1 / 3)))


def sphere_scene(path, frame):
    return {
        "version": 1,
        "seed": 3,
        # An empty [box]: the box is the file's configuration/box.
        "box": {},
        "species": [{"name": "A", "count": N_SPHERES}],
        "pair": [{"species": ["A", "A"], "steps": [[1.0, float("inf")]]}],
        "init": {
            "positions": "file",
            "file": str(path),
            "frame": frame,
            "velocities": "file",
            "temperature": 1.0,
        },
        "run": {"equilibration_events": 0, "events": 1000},
    }


def sphere_frames(rng, tilts=(0.0, 0.0, 0.0)):
    p0 = lattice(N_SIDE, L_SPHERES)
    v0 = rng.normal(size=(N_SPHERES, 3)).astype(np.float32)
    image0 = rng.integers(-2, 3, size=(N_SPHERES, 3)).astype(np.int32)
    # Lattice spacing 1.26σ; moves of at most 0.05σ per axis keep every pair apart.
    p1 = wrap(p0 + rng.uniform(-0.05, 0.05, size=p0.shape), L_SPHERES).astype(np.float32)
    frame0 = {
        "configuration/step": np.array([0], dtype=np.uint64),
        "configuration/dimensions": np.array([3], dtype=np.uint8),
        "configuration/box": box_chunk(L_SPHERES, tilts),
        "particles/N": np.array([N_SPHERES], dtype=np.uint32),
        "particles/types": types_chunk(["A"]),
        # typeid (all 0), mass (all 1), diameter (all 1), orientation (identity): defaults,
        # left out as HOOMD leaves them out.
        "particles/position": p0,
        "particles/velocity": v0,
        "particles/image": image0,
    }
    frame1 = {
        "configuration/step": np.array([5000], dtype=np.uint64),
        "configuration/box": box_chunk(L_SPHERES, tilts),
        "particles/N": np.array([N_SPHERES], dtype=np.uint32),
        "particles/position": p1,
    }
    return [frame0, frame1], (p0, p1, v0, image0)


def test_spheres_start_from_a_hoomd_layout_frame_with_frame_0_fallback(tmp_path):
    rng = np.random.default_rng(1)
    path = tmp_path / "hoomd-spheres.gsd"
    frames, (p0, p1, v0, image0) = sphere_frames(rng)
    write_hoomd_gsd(path, frames)

    last = dmdsim.load(sphere_scene(path, -1))
    assert last.n == N_SPHERES
    np.testing.assert_array_equal(last.box_lengths, [L_SPHERES] * 3)
    box = last.box_lengths
    # Positions of frame 1 (its own chunk), to single precision.
    assert same_point(last.positions, p1, box) < 1e-6 * L_SPHERES
    # Velocities and image counters are frame 0's: frame 1 does not store them.
    np.testing.assert_allclose(last.velocities, v0, rtol=0, atol=1e-6)
    unwrapped = p1 + image0 * L_SPHERES
    offset = last.unwrapped_positions - unwrapped
    assert np.abs(offset - offset[0]).max() < 1e-5 * L_SPHERES
    # Frame 0 itself.
    first = dmdsim.load(sphere_scene(path, 0))
    assert same_point(first.positions, p0, box) < 1e-6 * L_SPHERES
    np.testing.assert_allclose(first.velocities, v0, rtol=0, atol=1e-6)
    # The start runs.
    last.advance()
    assert last.summary()["events"] == 1000
    assert last.summary()["relative_energy_drift"] < 1e-10


def test_a_frame_without_velocities_anywhere_is_refused_by_name(tmp_path):
    rng = np.random.default_rng(2)
    frames, _ = sphere_frames(rng)
    del frames[0]["particles/velocity"]
    path = tmp_path / "no-velocity.gsd"
    write_hoomd_gsd(path, frames)
    with pytest.raises(dmdsim.SceneError, match="init.velocities.*particles/velocity"):
        dmdsim.load(sphere_scene(path, -1))


def test_a_tilted_box_is_refused_naming_init_file(tmp_path):
    rng = np.random.default_rng(3)
    frames, _ = sphere_frames(rng, tilts=(0.1, 0.0, 0.0))
    path = tmp_path / "tilted.gsd"
    write_hoomd_gsd(path, frames)
    with pytest.raises(dmdsim.SceneError) as e:
        dmdsim.load(sphere_scene(path, -1))
    message = str(e.value)
    assert "init.file" in message
    assert "tilt" in message and "orthorhombic" in message


# ---- rods: anisotropic bodies with orientations, moments of inertia and angular momenta -------

N_ROD_SIDE = 6
N_RODS = N_ROD_SIDE**3
ROD_DENSITY = 0.0178853806  # per Å³, the paper's ρ* = 0.5
ROD_MASS = 18.0  # g/mol
ROD_INERTIA = 1.154  # g/mol·Å², about the short axes (none about the axis)
L_RODS = float(np.float32((N_RODS / ROD_DENSITY) ** (1 / 3)))


def rod_frames(rng):
    """Frame 0 with every attribute, frame 1 with what HOOMD writes every frame when asked for
    `dynamic=["property", "momentum"]` (positions, orientations, velocities, angular momenta,
    images); the type names, masses and moments of inertia come from frame 0."""
    p0 = lattice(N_ROD_SIDE, L_RODS)
    frames = []
    states = []
    for step in (0, 2000):
        q = random_quaternions(rng, N_RODS)
        p = wrap(p0 + rng.uniform(-0.05, 0.05, size=p0.shape), L_RODS).astype(np.float32)
        v = rng.normal(scale=5.0, size=(N_RODS, 3))  # Å/ps
        # A rod turns about its short axes only: ω in the body frame has no z part.
        w_body = np.concatenate([rng.normal(scale=20.0, size=(N_RODS, 2)), np.zeros((N_RODS, 1))], 1)
        l_body = ROD_INERTIA * w_body
        # HOOMD's angular momentum quaternion: 2 q ⊗ (0, L_body).
        angmom = 2.0 * qmul(q, np.concatenate([np.zeros((N_RODS, 1)), l_body], axis=1))
        frame = {
            "configuration/step": np.array([step], dtype=np.uint64),
            "configuration/box": box_chunk(L_RODS),
            "particles/N": np.array([N_RODS], dtype=np.uint32),
            "particles/position": p,
            "particles/orientation": q.astype(np.float32),
            "particles/velocity": v.astype(np.float32),
            "particles/angmom": angmom.astype(np.float32),
        }
        if step == 0:
            frame.update(
                {
                    "configuration/dimensions": np.array([3], dtype=np.uint8),
                    "particles/types": types_chunk(["rod"]),
                    "particles/mass": np.full(N_RODS, ROD_MASS, dtype=np.float32),
                    "particles/moment_inertia": np.tile(
                        np.array([ROD_INERTIA, ROD_INERTIA, 0.0], dtype=np.float32), (N_RODS, 1)
                    ),
                    "particles/type_shapes": types_chunk(
                        ['{"type": "Ellipsoid", "a": 1.5, "b": 1.5, "c": 2.5}']
                    ),
                }
            )
        frames.append(frame)
        states.append((p, q.astype(np.float32), v.astype(np.float32), w_body))
    return frames, states


def rod_start(path, frame):
    return {
        "box.density": None,  # the box is the file's
        "output": None,
        "species.0.count": N_RODS,
        "init.positions": "file",
        "init.file": str(path),
        "init.frame": frame,
        "init.orientations": "file",
        "init.velocities": "file",
        "run.equilibration_time": 0.0,
        "run.time": 0.02,
    }


def test_rods_start_from_a_hoomd_layout_frame_of_anisotropic_particles(tmp_path):
    rng = np.random.default_rng(4)
    path = tmp_path / "hoomd-rods.gsd"
    frames, states = rod_frames(rng)
    write_hoomd_gsd(path, frames)
    for k in (0, -1):
        p, q, v, w_body = states[k]
        sim = dmdsim.load(SCENES / "rods-paper.toml", set=rod_start(path, k))
        assert sim.n == N_RODS
        assert sim.species_names == ["rod"]
        np.testing.assert_array_equal(sim.box_lengths, [L_RODS] * 3)
        assert same_point(sim.positions, p, sim.box_lengths) < 1e-6 * L_RODS
        # The attitude read back: a rod is its axis, the image of body z (its turn about the
        # axis carries nothing: no moment of inertia there).
        qn = q / np.linalg.norm(q, axis=1, keepdims=True)
        z = np.tile([0.0, 0.0, 1.0], (N_RODS, 1))
        np.testing.assert_allclose(rotate(sim.quaternions, z), rotate(qn, z), rtol=0, atol=1e-6)
        np.testing.assert_allclose(sim.velocities, v, rtol=0, atol=1e-5)
        # ω = q ω_body q*, from angmom divided by the moments about the short axes.
        omega = rotate(qn, w_body)
        scale = np.abs(omega).max()
        np.testing.assert_allclose(sim.angular_velocities, omega, rtol=0, atol=1e-5 * scale)
    # And it runs (NVE from the file's state).
    sim.advance()
    assert sim.summary()["relative_energy_drift"] < 1e-6
