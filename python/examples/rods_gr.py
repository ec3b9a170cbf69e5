"""The rods of van Zon & Schofield (2008), shortened, and their centre-of-mass g(r).

Runs scenes/rods-paper.toml (512 rigid rods on energy terraces, T* = 1.4, ρ* = 0.5, in Å, ps
and kJ/mol) with 2 ps of equilibration and 4 ps of production instead of 10 and 20, and plots
g(r) with matplotlib into rods_gr.png. From the root of a clone, after `pip install ./python
matplotlib`:

    python3 python/examples/rods_gr.py            # about 10 s
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt

import dmdsim

ROOT = Path(__file__).resolve().parents[2]
OUT = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/rods-gr")

summary = dmdsim.run(
    ROOT / "scenes" / "rods-paper.toml",
    out=OUT,
    set={
        "run.equilibration_time": 2.0,  # ps
        "run.time": 4.0,  # ps
        # g(r) only: the time correlations need longer runs.
        "output.msd": None,
        "output.vacf": None,
        "output.orientation_acf": None,
    },
    force=True,
)
rdf = dmdsim.read_observables(OUT)["rdf"]

print(
    f"{summary['n_bodies']} rods, {summary['sim_time']:.1f} ps: T = {summary['temperature']:.1f} K, "
    f"P = {summary['pressure']:.0f} bar, {summary['events_per_ps']:.3g} pair events per ps"
)

fig, ax = plt.subplots(figsize=(6, 4))
ax.plot(rdf["r"], rdf["g"], lw=1.5)
ax.axhline(1.0, color="grey", lw=0.8, ls="--")
ax.set_xlabel("centre-of-mass distance r (Å)")
ax.set_ylabel("g(r)")
ax.set_title(f"LJ rods, T = {summary['temperature']:.0f} K, ρ* = 0.5 ({summary['sim_time']:.0f} ps)")
ax.set_xlim(0.0, rdf["r"].max())
fig.tight_layout()
fig.savefig(OUT / "rods_gr.png", dpi=150)
print(f"wrote {OUT / 'rods_gr.png'}")
