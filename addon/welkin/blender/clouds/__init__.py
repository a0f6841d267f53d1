"""Welkin Clouds: procedural layers, marked VDB volumes, ground shadows."""
