"""Values the command line shows or checks before it runs anything, importable alone.

Each belongs to a module of a heavier package or layer (named beside it), which imports
it from here: one definition. They live here, at the bottom of the layers and beside
nothing that imports numpy or scipy, so that ``calstation CMD --help`` and a refused
argument answer without loading them (``tests/test_cli_entry.py``).
"""

from typing import Annotated, Final, Literal, get_args

from pydantic import StringConstraints

# The station's loop (station.loop.config).

#: Most slots a fixture holds (one USB serial port each).
MAX_SLOTS: Final = 8

# The putter link (station.device.protocol).

#: Largest sample rate the firmware accepts, samples/s.
MAX_RATE_HZ: Final = 1000
DEFAULT_RATE_HZ: Final = 500

# The run record (station.domain.record.records).

#: A station, operator or lot name (query filters use it too).
IDENTIFIER_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$"

Identifier = Annotated[str, StringConstraints(pattern=IDENTIFIER_PATTERN)]
"""A station, operator, algorithm or limits-profile name."""

#: A product's part number (station.domain.product.products): letters, digits and ``-._``.
PART_NUMBER_PATTERN = r"^[A-Z0-9][A-Z0-9._\-]{0,31}$"

PartNumber = Annotated[str, StringConstraints(pattern=PART_NUMBER_PATTERN)]
"""A product's part number (``DIXX-A12``)."""

#: What a value of each pattern above is, in the words a person refused one reads.
PATTERN_WORDS: Final = {
    IDENTIFIER_PATTERN: "a name is 1 to 64 letters, digits and . _ : @ -, no spaces, "
    "starting with a letter or digit (e.g. qa.kim)",
    PART_NUMBER_PATTERN: "a part number is 1 to 32 capital letters, digits and . _ -, "
    "starting with a letter or digit (e.g. DIXX-A12)",
}

#: The product of every run from before products existed (migration 0014), and of a
#: station configured with none: the putter with the KXM52 behind a 12-bit ADC.
DEFAULT_PART_NUMBER: Final = "DIXX-A12"

#: What a quality review decides for a unit on hold: calibrate it again, or scrap it.
ReviewDecision = Literal["retest", "scrap"]

# The gyros (station.domain.gyro).

#: Significance level of the error model's tests (station.domain.gyro.fit).
DEFAULT_ALPHA: Final = 0.01
#: Paper's fitted g-sensitivity, X / Y / Z gyro, ppm/g ([Park2014]_ section 2.4;
#: station.domain.gyro.simulate).
PAPER_PPM_PER_G = (581.0, 612.0, -613.0)
#: Sense axis of each gyro (x → y, y → z, z → y): the paper's Z gyro saw acceleration on
#: its sense axis in the mount whose X gyro did (its Fig. 8), so both sense along y.
DEFAULT_SENSE_AXES = (1, 2, 1)
#: Still window of a recorded stream, s: a hand-held pose is held one to a few seconds
#: (station.domain.gyro.motion.stream).
STILL_WINDOW_S: Final = 1.0

# The end-of-line report (station.report.render).

#: The formats the report is rendered in.
Format = Literal["text", "csv", "json", "html"]
FORMATS: tuple[str, ...] = get_args(Format)
