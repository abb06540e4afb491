"""demseis.dem: 2D discrete element model (lattice-solid / frictional-cohesive physics).

Public API (see docs/interfaces.md and docs/dem.md)::

    from demseis.dem import Material, NormalFault, build_assembly, simulate
    asm = build_assembly(5000.0, 2770.0, n_layers=48, rng=np.random.default_rng(0))
    snaps = simulate(asm, NormalFault(), Material(), n_snapshots=6)

``settle_pack`` (+ ``cache_dir``) makes the settled packing reusable across runs that share a
geometry; ``build_assembly(..., pack=...)`` then only assigns layers.
"""

from demseis.dem.assembly import Assembly, Pack, build_assembly, settle_pack
from demseis.dem.engine import Engine, time_step
from demseis.dem.fault import simulate
from demseis.dem.types import Material, NormalFault

__all__ = ["Assembly", "Engine", "Material", "NormalFault", "Pack",
           "build_assembly", "settle_pack", "simulate", "time_step"]
