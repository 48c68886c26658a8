"""An authorised signatory's Ed25519 signature of a certificate: a signed record
verifies under its signatory's key; one changed digit of the record, or a signature made
with another signatory's key, is refused in one line."""

import json
import re
from datetime import UTC, datetime

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.record.records import Coefficients
from station.domain.record.signature import (
    SignatureMismatchError,
    SignedCertificate,
    load_private_key,
    new_key,
    sign,
    verify,
)
from station.report.certificate import document_number
from tests.db.records import make_record

AT = datetime(2026, 11, 3, 9, 0, tzinfo=UTC)
ANN_PEM, ANN = new_key()
BOB_PEM, BOB = new_key()
RECORD = make_record()


def _signed(pem: bytes = ANN_PEM, signatory: str = "ann") -> SignedCertificate:
    key = load_private_key(pem, "key.pem")
    signature = sign(RECORD, document_number(RECORD), signatory, key, AT)
    return SignedCertificate(record=RECORD, signature=signature)


def test_a_signed_certificate_verifies_under_its_signatory_s_key() -> None:
    signed = _signed()
    verify(signed, ANN)
    again = SignedCertificate.model_validate_json(signed.model_dump_json())
    verify(again, ANN)  # the file's round trip changes nothing signed


#: The coefficients as the signed file holds them.
COEFFICIENTS = json.dumps(json.loads(_signed().model_dump_json())["record"]["coefficients"])


def _changed(where: int, by: int) -> str:
    """The coefficients' text with the digit at ``where`` raised by ``by`` (mod 10)."""
    digit = str((int(COEFFICIENTS[where]) + by) % 10)
    return COEFFICIENTS[:where] + digit + COEFFICIENTS[where + 1 :]


def _a_change(where: int, by: int) -> bool:
    """Whether that digit's change is one of the record: JSON still (no leading zero), a
    coefficient a record can hold, and another value (a double's 17th digit may name the
    same double)."""
    try:
        changed = json.loads(_changed(where, by))
        Coefficients.model_validate(changed)
    except ValueError:
        return False
    return bool(changed != json.loads(COEFFICIENTS))


#: Every one-digit change of the coefficients that changes the record.
CHANGES = [
    (m.start(), by)
    for m in re.finditer(r"\d", COEFFICIENTS)
    for by in range(1, 10)
    if _a_change(m.start(), by)
]


@settings(max_examples=40, deadline=None)
@given(change=st.sampled_from(CHANGES))
def test_one_changed_digit_of_a_coefficient_is_refused(change: tuple[int, int]) -> None:
    document = json.loads(_signed().model_dump_json())
    document["record"]["coefficients"] = json.loads(_changed(*change))
    signed = SignedCertificate.model_validate(document)
    with pytest.raises(SignatureMismatchError, match="the record was changed after it was signed"):
        verify(signed, ANN)


def test_another_signatory_s_key_is_refused() -> None:
    # Bob signs, claiming to be Ann: the signature does not verify under Ann's key.
    forged = _signed(BOB_PEM, "ann")
    with pytest.raises(SignatureMismatchError, match="the signature is not ann's") as caught:
        verify(forged, ANN)
    assert "\n" not in str(caught.value)
    # The statement's hash edited to a record's other hash: the signature no longer holds.
    signed = _signed()
    other = signed.signature.model_copy(update={"record_sha256": "0" * 64})
    tampered = signed.model_copy(update={"signature": other})
    with pytest.raises(SignatureMismatchError):
        verify(tampered, ANN)
    verify(_signed(BOB_PEM, "bob"), BOB)


def test_a_key_file_that_is_not_an_ed25519_pem_is_one_line() -> None:
    with pytest.raises(InputError, match=r"key\.pem: not an unencrypted PEM private key"):
        load_private_key(b"not a key", "key.pem")
