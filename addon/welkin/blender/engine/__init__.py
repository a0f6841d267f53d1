# SPDX-License-Identifier: GPL-3.0-or-later
"""The WELKIN render engine and its viewport preview."""
