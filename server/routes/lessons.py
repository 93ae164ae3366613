"""The seven lessons' live computations over REST: /api/lessons/... (see server/lessons/).

Every endpoint answers from the served model(s) and the corpus at request time; a bad parameter
gets a 4xx with a message a learner can act on.
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, Request

from server.deps import CorpusDep, JobsDep, ModelsDep, SettingsDep, SurveyDep
from server.lessons import LESSONS
from server.lessons.abstracting import stored_sweeps
from server.lessons.associating import associating as associate
from server.lessons.feeling import feeling as feel
from server.lessons.generalising import generalising as generalise
from server.lessons.seeing import decode_image
from server.lessons.seeing import seeing as see
from server.lessons.speaking import speak
from server.lessons.timescales import leaky_pulse, timescale_activity
from server.routes.forms import read_upload
from server.schemas.common import Problem
from server.schemas.lessons import (
    Activity,
    Association,
    CosineRun,
    CosineStart,
    Feeling,
    Generalisation,
    LessonIndex,
    LessonInfo,
    Pulse,
    SceneChoice,
    Seen,
    Speech,
    Sweeps,
)

router = APIRouter(prefix="/api/lessons", tags=["lessons"])

MAX_IMAGE_BYTES = 8 * 1024 * 1024
ERRORS: dict[int | str, dict[str, Any]] = {
    404: {"model": Problem},
    409: {"model": Problem},
    413: {"model": Problem},
    422: {"model": Problem},
    503: {"model": Problem},
}


# --- endpoints --------------------------------------------------------------------------------


@router.get("", response_model=LessonIndex)
def index(corpus: CorpusDep, models: ModelsDep) -> LessonIndex:
    """The lessons, the models and one recording per scene to choose from."""
    served = models.served
    firsts: dict[str, Any] = {}
    for e in corpus.entries.values():
        if e.scene.id not in firsts or e.variant < firsts[e.scene.id].variant:
            firsts[e.scene.id] = e
    return LessonIndex(
        lessons=[LessonInfo(id=i, title=t) for i, t in LESSONS],
        model=served.name,
        models=models.names(),
        modes=models.modes(),
        scenes=[
            SceneChoice(id=e.id, utterance=e.utterance, split=served.split_of(e.id, e.scene.id))
            for e in firsts.values()
        ],
    )


@router.get("/timescales/pulse", response_model=Pulse, responses=ERRORS)
def pulse(tau: Annotated[float, Query(description="timescale of the unit (1..200)")]) -> Pulse:
    """Lesson 1: one leaky integrator (eq. 3) answering a 10-step pulse."""
    return Pulse(**leaky_pulse(tau))


@router.get("/timescales/activity", response_model=Activity, responses=ERRORS)
def activity(
    corpus: CorpusDep, models: ModelsDep, scene: Annotated[str, Query(description="recording id")]
) -> Activity:
    """Lesson 1: MTRNN_a's IO, Cf and Cs activity while describing one recording."""
    return Activity(**timescale_activity(corpus, models, scene))


@router.get("/speaking", response_model=Speech, responses=ERRORS, response_model_by_alias=True)
def speaking(
    corpus: CorpusDep,
    text: Annotated[str, Query(description="a sentence of words the CMU dictionary knows")],
    gamma: Annotated[int, Query(description="head margin, eq. (19)")] = 4,
    omega: Annotated[int, Query(description="filter width, even")] = 4,
    sigma2: Annotated[float, Query(description="sigma^2, filter sharpness, eq. (18)")] = 0.3,
    nu: Annotated[int, Query(description="steps between two phonemes")] = 2,
) -> Speech:
    """Lesson 2: text -> phonemes -> spikes -> softmax (eqs. 18-21) -> decoder."""
    return Speech(**speak(text, gamma, omega, sigma2, nu, corpus.lexicon))


@router.get("/seeing", response_model=Seen, responses=ERRORS)
def seeing(
    corpus: CorpusDep,
    scene: Annotated[str, Query(description="recording id")],
    frame: Annotated[int, Query(description="frame index")] = 0,
    colour_radius: Annotated[int, Query(description="mean-shift colour window (4..64)")] = 24,
) -> Seen:
    """Lesson 3: the vision pipeline (Fig. 7) on one frame of a corpus recording."""
    frames = corpus.frames(scene)
    if not 0 <= frame < len(frames):
        raise HTTPException(422, f"{scene} has frames 0..{len(frames) - 1}, not {frame}")
    out = see(frames[frame], colour_radius)
    return Seen(**out, source=f"{scene}, frame {frame}", frames=len(frames))


IMAGE_FORM = {
    "requestBody": {
        "content": {
            "multipart/form-data": {
                "schema": {
                    "type": "object",
                    "required": ["image"],
                    "properties": {
                        "image": {
                            "type": "string",
                            "format": "binary",
                            "description": "a PNG or JPEG picture",
                        }
                    },
                }
            }
        }
    }
}


@router.post("/seeing", response_model=Seen, responses=ERRORS, openapi_extra=IMAGE_FORM)
async def seeing_upload(
    request: Request,
    colour_radius: Annotated[int, Query(description="mean-shift colour window (4..64)")] = 24,
) -> Seen:
    """Lesson 3: the vision pipeline on an uploaded picture (multipart field ``image``)."""
    too_large = HTTPException(413, f"the picture is larger than {MAX_IMAGE_BYTES // (1024 * 1024)} MB")
    data, filename = await read_upload(request, "image", "picture", MAX_IMAGE_BYTES, too_large)
    out = see(decode_image(data), colour_radius)
    return Seen(**out, source=filename or "upload")


@router.get("/feeling", response_model=Feeling, responses=ERRORS)
def feeling(
    corpus: CorpusDep,
    survey: SurveyDep,
    action: Annotated[str, Query(description="pull, push, show me or slide")] = "push",
    colour: Annotated[str, Query(description="blue, green, red or yellow")] = "red",
) -> Feeling:
    """Lesson 4: one action on the four shapes, and why touch alone cannot tell objects apart."""
    return Feeling(**feel(corpus, survey, action.replace("-", " "), colour))


@router.post("/abstracting/runs", response_model=CosineRun, responses=ERRORS, status_code=202)
def start_cosine(jobs: JobsDep, body: CosineStart) -> CosineRun:
    """Lesson 5: start the cosine experiment (3.2.2) for one psi; poll the run for its progress."""
    return CosineRun(**jobs.start_cosine(body.psi, body.seed).public())


@router.get("/abstracting/runs/{run_id}", response_model=CosineRun, responses=ERRORS)
def cosine_run(
    jobs: JobsDep,
    run_id: str,
    since: Annotated[int, Query(ge=0, description="only the Csc frames from this index on")] = 0,
) -> CosineRun:
    """Lesson 5: progress of a cosine run, with the Csc points recorded so far."""
    return CosineRun(**jobs.cosine_run(run_id).public(since))


@router.get("/abstracting/sweep", response_model=Sweeps)
def sweep(settings: SettingsDep) -> Sweeps:
    """Lesson 5: the stored psi_s and cosine sweeps of the protocol's run store ($MTRNN_RUN_DIR), else
    of the shipped report ($MTRNN_FIGURES_DIR/results.json)."""
    return Sweeps(**stored_sweeps(settings.run_dir, settings.figures_dir))


@router.get("/associating", response_model=Association, responses=ERRORS)
def associating(
    corpus: CorpusDep,
    models: ModelsDep,
    survey: SurveyDep,
    scene: Annotated[str, Query(description="recording id")],
    mute: Annotated[str, Query(description="none, vision or proprioception")] = "none",
) -> Association:
    """Lesson 6: the three Csc spaces (Fig. 10) and what the model says with one sense muted."""
    return Association(**associate(corpus, models, survey, scene, mute))


@router.get("/generalising", response_model=Generalisation, responses=ERRORS)
def generalising(
    corpus: CorpusDep,
    models: ModelsDep,
    survey: SurveyDep,
    model: Annotated[str | None, Query(description="model name (default: the served one)")] = None,
) -> Generalisation:
    """Lesson 7: training vs novel scenes for one model."""
    return Generalisation(**generalise(corpus, models, survey, model))
