"""Study commands: each runs one model of a node package on its own (no bus), prints its
result beside the thesis's numbers, and has ``--json`` where another tool reads it. The
numerics live with their models (``nodes.*``, pure functions); these modules only parse
arguments and print.

=========================  ==============================================================
module                     command
=========================  ==============================================================
``arm_card``               ``suscosim arm [--json]``: the lower arm's FE model card
``equivalent_lumped``      ``suscosim equivalent-lumped [--json]``: Appendix II
``bump_stop``              ``python -m orchestrator.studies.bump_stop``: where the corner
                           meets its bumper
``tyre_step``              ``python -m orchestrator.studies.tyre_step``: point contact vs
                           fixed footprint on the Ch. 3 step
=========================  ==============================================================
"""
