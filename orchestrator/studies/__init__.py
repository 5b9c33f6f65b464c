"""Study commands: each runs one model of a node package on its own (no bus) and prints its
result beside the thesis's numbers (``--json`` where another tool reads it); the numerics live
with their models (``nodes.*``). ``arm_card``: ``suscosim arm``, the lower arm's FE model card;
``equivalent_lumped``: ``suscosim equivalent-lumped`` (Appendix II); ``bump_stop`` and
``tyre_step`` (``python -m orchestrator.studies.<name>``): where the corner meets its bumper,
point contact vs fixed footprint on the Ch. 3 step.
"""
