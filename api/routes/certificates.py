"""A certificate's signature, verified by the server: the stored one of a run
(``GET /api/v1/runs/{run_id}/signature``, the certificate page's verify link), the signed
file to verify offline (``GET /api/v1/runs/{run_id}/certificate.json``), and a signed
file sent to it (``POST /api/v1/certificates/verify``). What is signed and how it is
checked: :mod:`station.domain.record.signature`; against which key: :mod:`db.store.signatures`."""

from datetime import datetime
from uuid import UUID

from fastapi import APIRouter, HTTPException, status
from fastapi.responses import Response
from pydantic import BaseModel
from sqlalchemy.orm import Session

from api.deps import ReaderDep
from api.errors import invalid
from api.responses import json_response, problems
from db import RunRepository
from db.store import signed_certificate, verify_signed
from station.domain.errors import InputError
from station.domain.record.signature import SignedCertificate

router = APIRouter(tags=["certificates"])


class SignatureCheck(BaseModel):
    """The verdict on a certificate's signature: ``valid`` when the record is the one
    signed and the signature is the signatory's under their registered key; else
    ``problem`` says which does not match, in one line."""

    valid: bool
    certificate: str
    signatory: str
    signed_at: datetime
    record_sha256: str
    problem: str | None = None


def _checked(signed: SignedCertificate, problem: str | None) -> SignatureCheck:
    signature = signed.signature
    return SignatureCheck(
        valid=problem is None,
        certificate=signature.certificate,
        signatory=signature.signatory,
        signed_at=signature.signed_at,
        record_sha256=signature.record_sha256,
        problem=problem,
    )


async def _signed(run_id: UUID, repository: ReaderDep) -> SignedCertificate:
    def read(r: RunRepository) -> SignedCertificate | None:
        run = r.get(run_id)
        return None if run is None else signed_certificate(r.session, run)

    signed = await repository.run(read)
    if signed is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no signed certificate of run {run_id}")
    return signed


@router.get(
    "/runs/{run_id}/signature",
    response_model=SignatureCheck,
    responses=problems(404, _404="no such run, or its certificate is not signed"),
)
async def get_signature(run_id: UUID, repository: ReaderDep) -> Response:
    """The stored signature of the run's certificate, verified now against the stored
    record and the signatory's registered key."""
    signed = await _signed(run_id, repository)
    problem = await repository.run(lambda r: _problem(r.session, signed))
    return json_response(_checked(signed, problem))


@router.get(
    "/runs/{run_id}/certificate.json",
    response_model=SignedCertificate,
    responses=problems(404, _404="no such run, or its certificate is not signed"),
)
async def get_signed_certificate(run_id: UUID, repository: ReaderDep) -> Response:
    """The signed certificate file of the run: its record and the signature, as
    ``calstation certificate verify FILE`` checks it."""
    return json_response(await _signed(run_id, repository))


@router.post(
    "/certificates/verify",
    response_model=SignatureCheck,
    responses=problems(
        400,
        422,
        _422="not a signed certificate, or one that does not verify: the record's SHA-256 is "
        "not the one signed, the signature is not the signatory's, or the signatory is not "
        "registered (one line)",
    ),
)
async def verify_certificate(signed: SignedCertificate, repository: ReaderDep) -> Response:
    """Verify a signed certificate file against its signatory's registered key."""
    problem = await repository.run(lambda r: _problem(r.session, signed))
    if problem is not None:
        raise invalid(("body", "signature"), problem)
    return json_response(_checked(signed, None))


def _problem(session: Session, signed: SignedCertificate) -> str | None:
    """Why ``signed`` does not verify; None when it does."""
    try:
        verify_signed(session, signed)
    except InputError as exc:
        return str(exc)
    return None
