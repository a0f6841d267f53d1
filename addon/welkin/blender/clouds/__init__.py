# SPDX-License-Identifier: GPL-3.0-or-later
"""Welkin Clouds: procedural layers, marked VDB volumes, ground shadows."""
