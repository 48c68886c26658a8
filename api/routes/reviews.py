"""``/api/v1/units/{serial}/reviews``: quality reviews of a unit on hold.

A unit whose latest run failed is on hold; one sent to rework is not calibrated again
until a review releases it (``retest``) or ends it (``scrap``). Reviews are append-only:
a unit's latest one decides (``docs/api.md``, *Units on hold*).
"""

import logging
from datetime import UTC, datetime

from fastapi import APIRouter, Response, status

from api.deps import QualityDep, ReaderDep, Repository, RepositoryDep
from api.responses import json_response, problems
from api.routes.units import SerialPath
from api.schemas import ReviewList, ReviewSubmission
from station.domain.record.records import HoldReview

log = logging.getLogger(__name__)

router = APIRouter(prefix="/units", tags=["reviews"])
#: Storing a review: a quality key only.
submissions = APIRouter(prefix="/units", tags=["reviews"])


@router.get("/{serial}/reviews", response_model=ReviewList)
async def get_unit_reviews(serial: SerialPath, repository: ReaderDep) -> Response:
    """Every review of the unit, oldest first (none: an empty list)."""
    reviews = await repository.run(lambda r: r.reviews(serial))
    return json_response(ReviewList(data=reviews, count=len(reviews)))


@submissions.post(
    "/{serial}/reviews",
    status_code=status.HTTP_201_CREATED,
    response_model=HoldReview,
    responses=problems(
        400,
        401,
        403,
        409,
        _403="the API key is not a quality engineer's",
        _409="the unit is not on hold, or the run is not its latest",
    ),
)
async def submit_unit_review(
    serial: SerialPath,
    submission: ReviewSubmission,
    reviewer: QualityDep,
    repository: RepositoryDep,
) -> Response:
    """Store a review of the unit's latest, failed run: its root cause, the repair, and
    whether the unit is calibrated again (``retest``) or scrapped."""
    review = await store_review(serial, submission, reviewer, repository)
    return json_response(review, status.HTTP_201_CREATED)


async def store_review(
    serial: str, submission: ReviewSubmission, reviewer: str, repository: Repository
) -> HoldReview:
    """Store ``reviewer``'s review of the unit (the API's and the unit page's form):
    :class:`db.ReviewRefusedError` when its run is not the unit's latest, failed one."""
    fields = submission.model_dump(include={"run_id", "root_cause", "repair_action", "decision"})
    review = HoldReview(serial=serial, reviewed_at=datetime.now(UTC), reviewer=reviewer, **fields)
    async with repository.session.begin():
        await repository.run(lambda r: r.add_review(review))
    log.info("review of %s: %s by %s", serial, review.decision, reviewer)
    return review
