"""Parts as data: a part file (TOML: geometry as STEP or a mesh, a material card, the
joints and their load channels; :func:`load_part`) -> the FE influence coefficients the
fatigue worker uses (:func:`.build.part_influence`), or unit cases solved elsewhere and
imported (CalculiX ``.frd``: :func:`.calculix.frd_influence`, ANSYS ``.rst``:
:func:`.ansys_rst.rst_influence`, Nastran ``.op2``: :func:`.nastran_op2.op2_influence`).
docs/parts.md, docs/importers.md. Only the part file's reader is imported here: every run's
preflight reads part files, and the FE (scikit-fem, gmsh) is imported where it is used.
"""

from .schema import Part, load_part

__all__ = ["Part", "load_part"]
