"""The WELKIN render engine and its viewport preview."""
