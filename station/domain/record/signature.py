"""An authorised signatory's signature of a calibration certificate (ISO/IEC 17025:2017
7.8.2.1 o: the identification of the person authorising the report; 7.8.2.2, 8.4: its
integrity).

A certificate is signed by signing its run's record: the record's canonical JSON (sorted
keys, no whitespace: :func:`station.domain.record.records.canonical_json`) is hashed with
SHA-256, and the signatory's Ed25519 key (RFC 8032, through ``cryptography``) signs the
canonical JSON of the statement ``{"certificate", "record_sha256", "signatory",
"signed_at"}``: the document's number, that hash, who signs and when. The signature is
detached: the signed file (:class:`SignedCertificate`, JSON) carries the record, its hash,
the statement's fields and the signature, and anyone holding the signatory's public key
verifies it (:func:`verify`): a record changed by one digit no longer has its hash, a
statement signed by another key does not verify under the signatory's.

Each signatory has a key of their own: the private key stays in a file they keep (PKCS #8
PEM, :func:`new_key`), the public key is registered under their name in the results
database, where the verification finds it.
"""

import base64
import binascii
import hashlib
from datetime import datetime
from typing import Annotated

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey
from pydantic import BaseModel, ConfigDict, Field

from station.domain.constants import IDENTIFIER_PATTERN
from station.domain.errors import InputError
from station.domain.record.records import RunRecord, UtcDatetime, canonical_json

#: A signatory's name: an identifier, as a station's or an operator's.
SignatoryName = Annotated[str, Field(pattern=IDENTIFIER_PATTERN)]
#: An Ed25519 signature, 64 bytes, as hex (128 digits).
SignatureHex = Annotated[str, Field(pattern=r"^[0-9a-f]{128}$")]
Sha256Hex = Annotated[str, Field(pattern=r"^[0-9a-f]{64}$")]


class SignatureMismatchError(InputError):
    """A signed certificate that does not verify: its record's hash or its signature."""


class Signature(BaseModel):
    """One signatory's signature of one certificate: the statement signed (the number,
    the record's SHA-256, who, when) and the Ed25519 signature over its canonical JSON."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    certificate: Annotated[str, Field(pattern=r"^CAL-\d{4}-[0-9A-F]{12}$")]
    record_sha256: Sha256Hex
    signatory: SignatoryName
    signed_at: UtcDatetime
    signature: SignatureHex

    def statement(self) -> bytes:
        """The bytes signed: the canonical JSON of the statement's four fields."""
        return statement(self.certificate, self.record_sha256, self.signatory, self.signed_at)


class SignedCertificate(BaseModel):
    """The signed certificate file: the run's record and its signature."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    record: RunRecord
    signature: Signature


def record_sha256(record: RunRecord) -> str:
    """SHA-256 of the record's canonical JSON (every field, sorted keys, no whitespace)."""
    return hashlib.sha256(canonical_record(record)).hexdigest()


def canonical_record(record: RunRecord) -> bytes:
    """The record's canonical JSON, as its hash is taken over it."""
    return canonical_json(station_record(record).model_dump(mode="json")).encode()


def station_record(record: RunRecord) -> RunRecord:
    """The station's record of a run: a stored run's own fields (when the server
    received it) left out."""
    return RunRecord.model_validate(record.model_dump(include=set(RunRecord.model_fields)))


def statement(certificate: str, sha256: str, signatory: str, signed_at: datetime) -> bytes:
    """The canonical JSON of what a signatory signs."""
    document = {
        "certificate": certificate,
        "record_sha256": sha256,
        "signatory": signatory,
        "signed_at": signed_at.isoformat(),
    }
    return canonical_json(document).encode()


def new_key() -> tuple[bytes, str]:
    """A new Ed25519 key: its private half as PKCS #8 PEM (the file the signatory keeps)
    and its public half as hex (registered)."""
    key = Ed25519PrivateKey.generate()
    pem = key.private_bytes(
        serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
    )
    return pem, public_hex(key)


def public_hex(key: Ed25519PrivateKey) -> str:
    """The public half of ``key``, 32 bytes as hex."""
    raw = key.public_key().public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    return raw.hex()


def load_private_key(pem: bytes, shown: str) -> Ed25519PrivateKey:
    """The Ed25519 private key of a PEM file (``shown``: its name in the error)."""
    try:
        key = serialization.load_pem_private_key(pem, password=None)
    except (ValueError, TypeError) as exc:
        raise InputError(f"{shown}: not an unencrypted PEM private key ({exc})") from None
    if not isinstance(key, Ed25519PrivateKey):
        raise InputError(f"{shown}: not an Ed25519 key")
    return key


def sign(
    record: RunRecord, certificate: str, signatory: str, key: Ed25519PrivateKey, at: datetime
) -> Signature:
    """``signatory``'s signature of the certificate ``certificate`` of ``record``, at ``at``."""
    sha256 = record_sha256(record)
    signed = key.sign(statement(certificate, sha256, signatory, at))
    return Signature(
        certificate=certificate,
        record_sha256=sha256,
        signatory=signatory,
        signed_at=at,
        signature=signed.hex(),
    )


def verify(signed: SignedCertificate, public_key: str) -> None:
    """Check ``signed`` against the signatory's registered ``public_key`` (hex): the
    record's hash is the one signed, and the signature is the key's over the statement.

    Raises :class:`SignatureMismatchError` naming which does not match.
    """
    signature = signed.signature
    sha256 = record_sha256(signed.record)
    if sha256 != signature.record_sha256:
        raise SignatureMismatchError(
            f"{signature.certificate}: the record's SHA-256 {sha256[:12]}… is not the signed "
            f"{signature.record_sha256[:12]}…: the record was changed after it was signed"
        )
    try:
        key = Ed25519PublicKey.from_public_bytes(binascii.unhexlify(public_key))
        key.verify(bytes.fromhex(signature.signature), signature.statement())
    except InvalidSignature:
        raise SignatureMismatchError(
            f"{signature.certificate}: the signature is not {signature.signatory}'s: it does not "
            "verify under their registered key"
        ) from None


def fingerprint(public_key: str) -> str:
    """A public key's short form for people: the first 16 characters of its SHA-256,
    base32 (as a page or a line shows which key signed)."""
    digest = hashlib.sha256(bytes.fromhex(public_key)).digest()
    return base64.b32encode(digest).decode()[:16]
