"""The parts of one unit's calibration run, one concern per module.

:class:`station.run.unit_run.UnitRun` drives a run through its phases (:mod:`.phases`) and
hands each step to the module that holds it:

- :mod:`.settings`: how a station runs its units (poses, tolerances, stillness, model);
- :mod:`.messages`: the sentences said to the operator;
- :mod:`.capture`: the pose being taken, its live view and when it is accepted;
- :mod:`.writeback`: writing the coefficients into the unit and reading them back;
- :mod:`.unit_output`: the unit's own calibrated output, checked after the write-back;
- :mod:`.reconnect`: reaching a unit again after its cable was pulled;
- :mod:`.checks`: the limit checks taken at the verdict;
- :mod:`.verdict`: the failures found, and the verdict they make;
- :mod:`.record`: the records built from what the run took;
- :mod:`.view`: the view model the unit screen reads.
"""
