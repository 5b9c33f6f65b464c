"""Parts as data: a part file (TOML: geometry as STEP or a mesh, a material card, the
joints and their load channels; :func:`load_part`) -> the FE influence coefficients the
fatigue worker uses (:func:`part_influence`), or unit cases solved elsewhere and imported
(CalculiX ``.frd``, ANSYS ``.rst``, Nastran ``.op2``). docs/parts.md, docs/importers.md.
"""

from .ansys_rst import rst_influence
from .build import part_influence
from .calculix import frd_influence
from .nastran_op2 import op2_influence
from .schema import Part, load_part

__all__ = ["Part", "frd_influence", "load_part", "op2_influence", "part_influence",
           "rst_influence"]
