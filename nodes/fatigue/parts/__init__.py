"""Parts as data: a part file (TOML: geometry as STEP or a mesh, a material card, the
joints and their load channels) -> the FE influence coefficients the fatigue worker uses.

API: ``load_part(path) -> Part`` (validated; a bad file is an `InputFileError` naming the
key), ``part_influence(part, mesh_size=None) -> InfluenceSet`` (the assessed surface nodes,
cached on disk), ``frd_influence(frd, case_names)`` (unit cases solved by CalculiX),
``rst_influence(rst, case_names)`` (unit cases solved by ANSYS MAPDL; needs
ansys-mapdl-reader, imported only when a file is read), ``op2_influence(op2, case_names)``
(unit cases solved by Nastran; needs pyNastran, run in a child process). Schema and the
built-in arm's design: docs/parts.md; the importers: docs/importers.md.
"""

from .ansys_rst import rst_influence
from .build import part_influence
from .calculix import frd_influence
from .nastran_op2 import op2_influence
from .schema import Part, load_part

__all__ = ["Part", "frd_influence", "load_part", "op2_influence", "part_influence",
           "rst_influence"]
