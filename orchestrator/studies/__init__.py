"""Study commands: one model of a node package run on its own (no bus, the numerics in
``nodes.*``), its result printed beside the thesis's numbers (``--json`` for other tools)."""
