"""``/api/v1/units/{serial}/reviews``: quality reviews of a unit on hold.

A unit whose latest run failed is on hold; one sent to rework is not calibrated again
until a review releases it (``retest``) or ends it (``scrap``). Reviews are append-only:
a unit's latest one decides (``docs/api.md``, *Units on hold*).
"""

import logging
from datetime import UTC, datetime

from fastapi import APIRouter, Response, status

from api.deps import QualityDep, ReaderDep, RepositoryDep
from api.responses import json_response, problems
from api.routes.units import SerialPath
from api.schemas import ReviewList, ReviewSubmission
from station.domain.records import HoldReview

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
    review = HoldReview(
        serial=serial, reviewed_at=datetime.now(UTC), reviewer=reviewer, **dict(submission)
    )
    async with repository.session.begin():
        await repository.run(lambda r: r.add_review(review))
    log.info("review of %s: %s by %s", serial, review.decision, reviewer)
    return json_response(review, status.HTTP_201_CREATED)
