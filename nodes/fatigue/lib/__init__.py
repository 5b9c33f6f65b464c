"""The fatigue library: pure numerics, no bus, no run-folder I/O.

Rainflow counting (`counting`), turning points of the equivalent stress (`turning_eq`), stress
superposition (`superposition`), equivalent stresses (`equivalent_stress`), S-N and strain-life
curves (`life_models`, `sn_data`, `fkm`, `material`), mean-stress corrections (`mean_stress`),
damage (`damage`, `pseudo_damage`, `duty_cycle`), screening (`screening`), the
critical plane (`critical_plane`), spectral methods (`spectral`), the influence set
(`influence_set`), the part FE on P2 tetrahedra (`solid`), closed-form arm bounds (`arm_bounds`)
and the result (`result`). Inputs come in as arrays and dataclasses; files, configuration, the
bus and run folders are the node's (:mod:`nodes.fatigue`), checked by
tests/fatigue/test_lib_pure.py.
"""
