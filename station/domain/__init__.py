"""The domain: what a unit, a pose, a run and a limit are, and the math that judges them.

Nothing here touches a port, a file the station keeps, a database or a screen: the
accelerometer calibration ([Song2006]_, :mod:`.calibration`), the gyros ([Park2014]_,
[Tedaldi2014]_, :mod:`.gyro`), stillness, limits and judging, the run record, a unit's
state, and the report's figures (:mod:`.quality`). Every other layer imports it; it
imports none of them.
"""
