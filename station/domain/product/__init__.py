"""The products: limits, judging, run plans and settings."""
