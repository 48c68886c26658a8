"""Link statistics: how healthy the serial line to the putter is."""

from dataclasses import asdict, dataclass, fields


@dataclass(frozen=True, slots=True)
class LinkStats:
    """Counters of one link since it was opened (or the difference of two snapshots).

    ``samples``: samples accepted; ``samples_lost``: samples missing according to the
    sequence numbers; ``seq_gaps``: places where samples went missing;
    ``crc_failures``, ``bad_headers``, ``resyncs``, ``bytes_discarded``: see
    :class:`station.device.protocol.FrameParser`; ``buffer_overruns``: samples pushed
    out of the driver's buffer because nobody drained it.
    """

    samples: int = 0
    samples_lost: int = 0
    seq_gaps: int = 0
    crc_failures: int = 0
    bad_headers: int = 0
    resyncs: int = 0
    bytes_discarded: int = 0
    buffer_overruns: int = 0

    @property
    def loss_fraction(self) -> float:
        """Fraction of the samples sent that never arrived (0 when none were expected)."""
        expected = self.samples + self.samples_lost
        return self.samples_lost / expected if expected else 0.0

    def __sub__(self, earlier: "LinkStats") -> "LinkStats":
        """Counters accumulated between ``earlier`` and this snapshot."""
        return LinkStats(
            **{f.name: getattr(self, f.name) - getattr(earlier, f.name) for f in fields(self)}
        )

    def to_dict(self) -> dict[str, float]:
        """Plain counters plus ``loss_fraction``, for JSON."""
        return {**asdict(self), "loss_fraction": self.loss_fraction}
