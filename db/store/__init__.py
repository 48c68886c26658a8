"""The store of runs and units: what a submission, a unit's page, certificates,
signatures, holds' reviews, keys and settings and run events write and read."""
