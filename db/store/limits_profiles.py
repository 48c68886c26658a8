"""Limits profiles in the results database: stored once per SHA-256, read by the report.

A run's submission carries its profile (:attr:`station.domain.record.records.LimitsRef.profile`);
:func:`store_profile` keeps its canonical JSON the first time a run uses it (one
``INSERT … ON CONFLICT DO NOTHING`` on the primary key). The report, the certificate
and the dashboard read profiles from here (:func:`stored_profiles`), never from a
limits file. A what-if's candidate profile is kept here too (:func:`keep_profile`), so
a link to the what-if names it by its SHA-256 and reproduces it; a profile no run
refers to is in no report's list of profiles (those are the runs' own).
"""

from collections.abc import Collection

from sqlalchemy import select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from db.engine import for_dialect
from db.models import StoredLimitsProfile
from station.domain.product.limits import LimitsProfile, profile_of
from station.domain.record.records import LimitsRef, canonical_json, document_sha256

_INSERT = {
    name: dialect.insert(StoredLimitsProfile).on_conflict_do_nothing(index_elements=["sha256"])
    for name, dialect in (("postgresql", postgresql), ("sqlite", sqlite))
}


def store_profile(session: Session, ref: LimitsRef) -> None:
    """Store the profile ``ref`` carries unless its SHA-256 is stored already.

    :class:`station.domain.errors.InputError` when the document is not a limits profile
    (:func:`station.domain.product.limits.profile_of`); the reference itself checked that it
    hashes to ``ref.sha256``, and the stored text is the text that hash was taken over.
    """
    profile = profile_of(ref)
    if profile is not None:
        keep_profile(session, profile)


def keep_profile(session: Session, profile: LimitsProfile) -> str:
    """Store ``profile`` unless its SHA-256 is stored already; its SHA-256."""
    row = profile_row(profile)
    session.execute(for_dialect(session, _INSERT), row)
    return row["sha256"]


def profile_row(profile: LimitsProfile) -> dict[str, str]:
    """The ``limits_profiles`` row of ``profile``: its canonical document, keyed by its hash.

    :func:`station.domain.product.limits.profile_of` checked that a submitted document is this one.
    """
    document = profile.document
    return {
        "sha256": document_sha256(document),
        "name": profile.name,
        "version": profile.version,
        "document": canonical_json(document),
    }


def stored_profiles(session: Session, sha256s: Collection[str]) -> dict[str, LimitsProfile]:
    """The stored profiles among ``sha256s``, by SHA-256."""
    if not sha256s:
        return {}
    rows = session.execute(
        select(StoredLimitsProfile.sha256, StoredLimitsProfile.document).where(
            StoredLimitsProfile.sha256.in_(sorted(sha256s))
        )
    )
    return {sha: LimitsProfile.model_validate_json(document) for sha, document in rows}
