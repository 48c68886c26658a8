"""Authorised signatories' public keys and their signatures of certificates, stored
(:mod:`station.domain.record.signature` says what is signed and how it is verified)."""

from datetime import UTC, datetime
from uuid import UUID

from sqlalchemy import select
from sqlalchemy.orm import Session

from db.models import CertificateSignature, Signatory
from station.domain.errors import InputError
from station.domain.record.records import RunRecord
from station.domain.record.signature import (
    Signature,
    SignatureMismatchError,
    SignedCertificate,
    station_record,
    verify,
)


def register_signatory(session: Session, name: str, public_key: str) -> None:
    """Register ``name``'s public key (hex); a name registered already is refused (its
    key stays the one that verifies what it signed)."""
    if signatory_key(session, name) is not None:
        raise InputError(f"signatory {name!r} is registered already")
    session.add(Signatory(name=name, public_key=public_key, created_at=datetime.now(UTC)))
    session.flush()


def signatory_key(session: Session, name: str) -> str | None:
    """The registered public key (hex) of signatory ``name``; None if none is."""
    return session.scalar(select(Signatory.public_key).where(Signatory.name == name))


def add_signature(session: Session, run_id: UUID, signature: Signature) -> None:
    """Store ``signature`` of run ``run_id``'s certificate; a certificate signed already
    is refused, naming who signed it."""
    signed = signature_of(session, run_id)
    if signed is not None:
        raise InputError(
            f"{signed.certificate} is signed already, by {signed.signatory} at "
            f"{signed.signed_at.isoformat()}"
        )
    session.add(CertificateSignature(run_id=run_id, **signature.model_dump()))
    session.flush()


def signature_of(session: Session, run_id: UUID) -> Signature | None:
    """The stored signature of run ``run_id``'s certificate, if it was signed."""
    row = session.scalar(select(CertificateSignature).where(CertificateSignature.run_id == run_id))
    return None if row is None else Signature.model_validate(row, from_attributes=True)


def verify_signed(session: Session, signed: SignedCertificate) -> None:
    """Check ``signed`` against its signatory's registered key: one place for the
    command line and the server. Raises :class:`SignatureMismatchError` when the record's
    hash or the signature does not match, :class:`InputError` when the signatory is not
    registered."""
    name = signed.signature.signatory
    key = signatory_key(session, name)
    if key is None:
        raise SignatureMismatchError(
            f"{signed.signature.certificate}: {name} is not a registered signatory"
        )
    verify(signed, key)


def signed_certificate(session: Session, run: RunRecord) -> SignedCertificate | None:
    """The signed certificate file of ``run``: its record and stored signature; None
    when its certificate is not signed."""
    signature = signature_of(session, run.run_id)
    if signature is None:
        return None
    return SignedCertificate(record=station_record(run), signature=signature)
