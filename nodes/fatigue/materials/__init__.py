"""Shipped material database (materials.toml); read by nodes.fatigue.material."""
