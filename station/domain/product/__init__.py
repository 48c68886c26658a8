"""The products: what a part number asks of a unit, and how a station runs it.

Products and their labels (``products``), limits profiles (``limits``) and the checks
that judge a run on them (``judging``), how long a pose's window must be
(``capture_budget``), the run plans and settings (``run_settings``, ``pose_plan``), and
the laboratory that issues the certificates (``laboratory``). Its shipped data is
``station/domain/profiles/``. Above the record, which it judges.
"""
