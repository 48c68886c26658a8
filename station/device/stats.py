"""Link statistics: how healthy the serial line to the putter is."""

from dataclasses import dataclass, fields


@dataclass(frozen=True, slots=True)
class LinkCounters:
    """Counters of one link since it was opened (or the difference of two snapshots).

    The four counters a pose's record stores keep the record's names
    (:class:`station.domain.record.records.LinkStats`): ``crc_errors`` (well-formed headers whose
    CRC
    did not match), ``gaps`` (places where samples went missing), ``resyncs`` (see
    :class:`station.device.protocol.FrameParser`) and ``lost_samples`` (samples
    missing according to the sequence numbers). The link also counts ``samples``
    accepted, ``bad_headers`` and ``bytes_discarded`` (see the parser) and
    ``buffer_overruns``: samples pushed out of the driver's buffer because nobody
    drained it.
    """

    samples: int = 0
    lost_samples: int = 0
    gaps: int = 0
    crc_errors: int = 0
    bad_headers: int = 0
    resyncs: int = 0
    bytes_discarded: int = 0
    buffer_overruns: int = 0

    @property
    def loss_fraction(self) -> float:
        """Fraction of the samples sent that never arrived (0 when none were expected)."""
        expected = self.samples + self.lost_samples
        return self.lost_samples / expected if expected else 0.0

    def __sub__(self, earlier: "LinkCounters") -> "LinkCounters":
        """Counters accumulated between ``earlier`` and this snapshot."""
        return LinkCounters(
            **{f.name: getattr(self, f.name) - getattr(earlier, f.name) for f in fields(self)}
        )
