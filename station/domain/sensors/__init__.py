"""The sensors: what the putter's hardware is and what it can send.

The constants of the putter's front end ([Song2006]_ Table 1, ``sensor``), a product's
accelerometer and gyros as the station reads them (``sensor_spec``), the bounds of every
number a record can hold, from the hardware and the wire (``record_bounds``), and the
faults the virtual putter can be told to show (``faults``). The lowest of the domain's
concepts: it imports none of them (``pyproject.toml``, contract ``domain-layers``).
"""
