"""The world's sky: the panel, the sky update, the world's images and nodes."""
