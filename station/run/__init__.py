"""One unit's calibration run, from its first pose to its record.

:class:`station.run.unit_run.UnitRun` drives a run through its phases (:mod:`.phases`)
and hands each step to the module that holds it:

- :mod:`.acquisition`: one still pose from the stream (the live still-window detector);
- :mod:`.capture`: the pose being taken, its live view and when it is accepted;
- :mod:`.writeback`: writing the coefficients into the unit and reading them back;
- :mod:`.unit_output`: the unit's own calibrated output, checked after the write-back;
- :mod:`.gyro_moves`, :mod:`.gyro`, :mod:`.gyro_check`: the whole unit's gyro matrix from
  the moves between poses, and the verification move;
- :mod:`.reconnect`: reaching a unit again after its cable was pulled;
- :mod:`.verdict`: the verdict, reached in one place, and the record built once;
- :mod:`.record`: the pose and run records built from what the run took;
- :mod:`.messages`, :mod:`.operator_text`, :mod:`.view`: what the operator is told, in
  the operator's words, and the view model the screens draw.
"""
