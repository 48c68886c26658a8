"""The sensors: what the putter's hardware is and can send."""
