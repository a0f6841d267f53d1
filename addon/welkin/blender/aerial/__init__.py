"""Aerial perspective for camera renders (Scene.welkin_aerial)."""
