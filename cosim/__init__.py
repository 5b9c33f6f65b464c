"""suscosim's shared core: wire format, bus, lock-step participant, scenario schema."""
