"""Part files shipped as package data (docs/parts.md)."""
