"""The store of runs and units: what a submission, a unit's page, certificates,
signatures, hold reviews, station keys and run events write and read, in the tables of
:mod:`db.models` (and the roll-ups of :mod:`db.rollups`, written with each run).
It never imports :mod:`db.report`, whose queries read what it stores.
"""

from db.store.certificates import certificate_inputs, certificate_run
from db.store.limits_profiles import keep_profile, profile_row, stored_profiles
from db.store.repository import (
    MAX_PAGE,
    KeyHolder,
    KeyScope,
    ReviewRefusedError,
    RunConflictError,
    RunQuery,
    RunRepository,
    SubmitOutcome,
)
from db.store.run_events import last_stored, stored_after
from db.store.signatures import (
    add_signature,
    register_signatory,
    signatory_key,
    signed_certificate,
    verify_signed,
)
from db.store.units import UnitLookups

__all__ = [
    "MAX_PAGE",
    "KeyHolder",
    "KeyScope",
    "ReviewRefusedError",
    "RunConflictError",
    "RunQuery",
    "RunRepository",
    "SubmitOutcome",
    "UnitLookups",
    "add_signature",
    "certificate_inputs",
    "certificate_run",
    "keep_profile",
    "last_stored",
    "profile_row",
    "register_signatory",
    "signatory_key",
    "signed_certificate",
    "stored_after",
    "stored_profiles",
    "verify_signed",
]
