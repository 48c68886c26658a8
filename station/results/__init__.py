"""The results plumbing: where a finished run goes and how it gets there.

The journal of the run in progress (:mod:`.journal`), the outbox every finished run waits
in (:mod:`.outbox`), the stores behind it (:mod:`.storage`: the database directly or the
results server; the station's one door to :mod:`db`, :mod:`api` and SQLAlchemy), and the
data disk under both (:mod:`.files`, :mod:`.disk`).
"""
