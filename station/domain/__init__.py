"""The domain: what a unit, a pose, a run and a limit are, and the math that judges them.

Nothing here touches a port, a file the station keeps, a database or a screen. Its
concepts, each a package, top to bottom (each imports only those below it): the report's
figures (:mod:`.quality`), the products, limits and plans (:mod:`.product`), the unit's
record and state (:mod:`.record`), the gyros ([Park2014]_, [Tedaldi2014]_, :mod:`.gyro`),
the accelerometer calibration ([Song2006]_, :mod:`.calibration`), the signals
(:mod:`.signals`) and the sensors (:mod:`.sensors`). Beside them, what all share:
constants, errors, the translations, TOML text, patterns. Every other layer imports it;
it imports none of them.
"""
