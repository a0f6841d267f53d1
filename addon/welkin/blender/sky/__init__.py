# SPDX-License-Identifier: GPL-3.0-or-later
"""The world's sky: the panel, the sky update, the world's images and nodes."""
