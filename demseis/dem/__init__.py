"""demseis.dem: 2D discrete element model (lattice-solid / frictional-cohesive physics).

Public API (see docs/interfaces.md and docs/dem.md)::

    from demseis.dem import Material, NormalFault, build_assembly, simulate
    asm = build_assembly(5000.0, 2770.0, n_layers=48, rng=np.random.default_rng(0))
    snaps = simulate(asm, NormalFault(), Material(), n_snapshots=6)

Reference coordinates of points of a deformed snapshot (where their rock was in the undeformed
model, or where it was deposited)::

    from demseis.dem import reference_map
    rm = reference_map(snaps, k, points_xy)   # rm.ref_xy, rm.layer, rm.deposited, rm.element

``settle_pack`` (+ ``cache_dir``) makes the settled packing reusable across runs that share a
geometry; ``build_assembly(..., pack=...)`` then only assigns layers.
"""

from demseis.dem.assembly import Assembly, Pack, PackCacheWarning, build_assembly, settle_pack
from demseis.dem.integrator import Integrator, time_step
from demseis.dem.basement import BasementFault, FaultSystem
from demseis.dem.fault import simulate
from demseis.dem.reference import (
    MapInfo,
    ReferenceMap,
    element_maps,
    reference_coordinates,
    reference_map,
)
from demseis.dem.types import BRITTLE, Material, NormalFault

__all__ = ["BRITTLE", "Assembly", "BasementFault", "FaultSystem", "Integrator", "MapInfo", "Material",
           "NormalFault", "Pack", "PackCacheWarning", "ReferenceMap", "build_assembly", "element_maps",
           "reference_coordinates", "reference_map", "settle_pack", "simulate", "time_step"]
