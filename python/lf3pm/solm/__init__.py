"""Static Observation Loss Maps (SOLM): the LF-3PM metric evaluated over a grid
of poses once per map, stored as Zarr, read by planners and people.

    from lf3pm.solm import Solm, Space, build_solm, make_grid
"""

from lf3pm.config import SPACES
from lf3pm.grid import Grid, Space
from lf3pm.solm.build import build_solm
from lf3pm.solm.grid import SolmGrid, make_grid
from lf3pm.solm.reader import Solm

__all__ = ["SPACES", "Grid", "Solm", "SolmGrid", "Space", "build_solm", "make_grid"]
