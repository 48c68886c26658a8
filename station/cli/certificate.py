"""``calstation certificate issue SERIAL``: the station's own calibration certificate of a
unit, from its results database, as the results server's page shows it;
``calstation certificate signatory NAME``, ``sign SERIAL`` and ``verify FILE``: an
authorised signatory's key, their signature of a certificate, and its check
(:mod:`station.domain.record.signature`)."""

# Light to import: --help and refused arguments read only the signatures below; each
# command imports its work (SQLAlchemy, the pages) when it runs.

from pathlib import Path
from typing import Annotated, cast

import typer

from station.cli.db import DatabaseUrlOption
from station.cli.output import err, out
from station.domain.errors import CalstationError, InputError

certificate_app = typer.Typer(
    help="Calibration certificates: issue, sign and verify; authorised signatories' keys.",
    no_args_is_help=True,
)


@certificate_app.command("issue")
def issue(
    serial: Annotated[str, typer.Argument(metavar="SERIAL", help="The unit's serial number.")],
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="The station's configuration (TOML) whose [laboratory] table names the "
            "laboratory, its address, where it calibrates, the customer and the traceability "
            "of its reference.",
            show_default=False,
        ),
    ] = None,
    language: Annotated[
        str, typer.Option("--language", help="The reader's language: en, ko or zh.")
    ] = "en",
    timezone: Annotated[
        str,
        typer.Option(
            "--timezone",
            envvar="CALSTATION_PLANT_TIMEZONE",
            help="The plant's time zone (IANA name): times shown in it.",
        ),
    ] = "UTC",
    shifts: Annotated[
        str,
        typer.Option(
            "--shifts",
            envvar="CALSTATION_PLANT_SHIFTS",
            help="The plant's shift start times: the shift whose golden-unit check is the "
            "reference.",
        ),
    ] = "",
    format: Annotated[
        str,
        typer.Option(
            "--format",
            help="html, or pdf (needs --out; in ko or zh it needs the Noto Sans CJK font, "
            "Debian's fonts-noto-cjk).",
        ),
    ] = "html",
    output: Annotated[
        Path | None,
        typer.Option("--out", help="Write to this file instead of standard output."),
    ] = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """The unit's calibration certificate (or failure report), HTML or PDF."""
    from datetime import UTC, datetime

    from db import repository_transaction
    from db.store import certificate_inputs
    from station.domain.i18n import LANGUAGES, Language
    from station.domain.product.laboratory import Laboratory, load_laboratory
    from station.domain.quality.shifts import parse_shifts
    from station.report.certificate_document import CertificateFormat, certificate_document
    from station.report.period import plant_zone

    if language not in LANGUAGES:
        raise InputError(f"--language {language!r} is not one of {', '.join(LANGUAGES)}")
    if format not in ("html", "pdf"):
        raise InputError(f"--format {format!r} is not one of html, pdf")
    if format == "pdf" and output is None:
        raise InputError("--format pdf needs --out FILE")
    reader = cast(Language, language)  # one of LANGUAGES, checked above
    zone = plant_zone(timezone)
    starts = parse_shifts(shifts)
    laboratory = Laboratory() if config is None else load_laboratory(config)
    with repository_transaction(database_url) as repository:
        found = certificate_inputs(repository, serial, zone, starts)
    if found is None:
        raise InputError(f"no calibration run of serial {serial!r}")
    document = certificate_document(
        found, cast(CertificateFormat, format), datetime.now(UTC), zone, reader, laboratory
    )
    if output is None:  # a page: --format pdf needs --out, checked above
        out.file.write(document.decode())
        out.file.flush()
        return
    _write(output, document)


def _write(output: Path, document: bytes) -> None:
    try:
        output.write_bytes(document)
    except OSError as exc:
        raise CalstationError(f"{output}: cannot write the certificate: {exc.strerror}") from None
    err.print(f"certificate written to {output}", markup=False)


KeyFileOption = Annotated[
    Path,
    typer.Option(
        "--key-file", help="The signatory's private key (PEM), kept by the signatory alone."
    ),
]


@certificate_app.command("signatory")
def signatory(
    name: Annotated[str, typer.Argument(metavar="NAME", help="The signatory (a name, no spaces).")],
    key_file: KeyFileOption,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Create an authorised signatory's Ed25519 key: the private key goes to --key-file
    (readable by its owner only), the public key is registered under NAME."""
    import os

    from pydantic import TypeAdapter, ValidationError

    from db import repository_transaction
    from db.store import register_signatory
    from station.domain.errors import validation_problem
    from station.domain.record.signature import SignatoryName, fingerprint, new_key

    try:
        TypeAdapter(SignatoryName).validate_python(name)
    except ValidationError as exc:
        raise InputError(f"signatory {name!r}: {validation_problem(exc)}") from None
    pem, public = new_key()
    with repository_transaction(database_url) as repository:
        register_signatory(repository.session, name, public)
        try:
            fd = os.open(key_file, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError as exc:
            raise CalstationError(f"{key_file}: cannot write the key: {exc.strerror}") from None
        with os.fdopen(fd, "wb") as file:
            file.write(pem)
    out.print(f"signatory {name}: key {fingerprint(public)}, private key in {key_file}")


@certificate_app.command("sign")
def sign(
    serial: Annotated[str, typer.Argument(metavar="SERIAL", help="The unit's serial number.")],
    by: Annotated[str, typer.Option("--by", help="The signatory signing (their NAME).")],
    key_file: KeyFileOption,
    output: Annotated[
        Path | None,
        typer.Option("--out", help="The signed file (JSON; default CAL-….json here)."),
    ] = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Sign the unit's calibration certificate as an authorised signatory: the signature
    is stored with the run and written, with the record, to the signed file."""
    from datetime import UTC, datetime

    from db import repository_transaction
    from db.store import add_signature, certificate_run, signatory_key, signed_certificate
    from station.domain.record.signature import load_private_key, public_hex
    from station.domain.record.signature import sign as sign_record
    from station.report.certificate import document_number

    try:
        pem = key_file.read_bytes()
    except OSError as exc:
        raise InputError(f"{key_file}: cannot read the key: {exc.strerror}") from None
    key = load_private_key(pem, str(key_file))
    with repository_transaction(database_url) as repository:
        registered = signatory_key(repository.session, by)
        if registered is None:
            raise InputError(f"{by} is not a registered signatory")
        if registered != public_hex(key):
            raise InputError(f"{key_file} is not {by}'s registered key")
        found = certificate_run(repository, serial)
        if found is None:
            raise InputError(f"no calibration run of serial {serial!r}")
        run = found[0]
        if run.verdict != "pass":
            raise InputError(f"{serial} is on hold (its latest run failed): nothing to certify")
        number = document_number(run)
        signature = sign_record(run, number, by, key, datetime.now(UTC))
        add_signature(repository.session, run.run_id, signature)
        signed = signed_certificate(repository.session, run)
    assert signed is not None
    path = output or Path(f"{number}.json")
    try:
        path.write_text(signed.model_dump_json(indent=1), encoding="utf-8")
    except OSError as exc:
        raise CalstationError(f"{path}: cannot write the signed file: {exc.strerror}") from None
    out.print(f"{number} signed by {by}: {path}")


@certificate_app.command("verify")
def verify(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="A signed certificate (JSON).")],
    database_url: DatabaseUrlOption = None,
) -> None:
    """Verify a signed certificate against its signatory's registered key: exit 0 when the
    record is the one signed and the signature is the signatory's, else one line, exit 2."""
    from pydantic import ValidationError

    from db import repository_transaction
    from db.store import verify_signed
    from station.domain.errors import validation_problem
    from station.domain.record.signature import SignedCertificate

    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) else "not UTF-8 text"
        raise InputError(f"{file}: cannot read the signed certificate: {reason}") from None
    try:
        signed = SignedCertificate.model_validate_json(text)
    except ValidationError as exc:
        raise InputError(f"{file}: not a signed certificate: {validation_problem(exc)}") from None
    with repository_transaction(database_url) as repository:
        verify_signed(repository.session, signed)
    signature = signed.signature
    out.print(
        f"{signature.certificate}: valid, signed by {signature.signatory} at "
        f"{signature.signed_at.isoformat()} (record SHA-256 {signature.record_sha256})"
    )
