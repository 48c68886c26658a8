"""The unit's record: runs, a unit's state, signatures."""
