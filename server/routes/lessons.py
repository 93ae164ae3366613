"""The seven lessons' live computations over REST: /api/lessons/... (see server/lessons.py).

Every endpoint answers from the served model(s) and the corpus at request time; a bad parameter
gets a 4xx with a message a learner can act on.
"""

from __future__ import annotations

import threading
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, File, HTTPException, Query, Request, UploadFile
from pydantic import BaseModel, Field

from model.experiments.protocol import default_run_dir
from server import lessons as L
from server.schemas import Problem
from server.state import AppState, get_state

router = APIRouter(prefix="/api/lessons", tags=["lessons"])

MAX_IMAGE_BYTES = 8 * 1024 * 1024
_create_lock = threading.Lock()  # guards the one-time creation of each app's LessonStore
ERRORS: dict[int | str, dict[str, Any]] = {
    404: {"model": Problem},
    409: {"model": Problem},
    413: {"model": Problem},
    422: {"model": Problem},
    503: {"model": Problem},
}


def get_lessons(request: Request, state: Annotated[AppState, Depends(get_state)]) -> L.LessonStore:
    """FastAPI dependency: this app's LessonStore, created on first use next to its AppState."""
    store = getattr(request.app.state, "lessons", None)
    if store is None or store.state is not state:
        with _create_lock:
            store = getattr(request.app.state, "lessons", None)
            if store is None or store.state is not state:
                store = L.LessonStore(state)
                request.app.state.lessons = store
    return store


LessonsDep = Annotated[L.LessonStore, Depends(get_lessons)]


def _call(fn: Any, *args: Any, **kwargs: Any) -> Any:
    try:
        return fn(*args, **kwargs)
    except L.LessonError as err:
        raise HTTPException(err.status, str(err)) from None


# --- schemas ---------------------------------------------------------------------------------


class LessonInfo(BaseModel):
    id: str
    title: str


class SceneChoice(BaseModel):
    id: str
    utterance: str
    split: str


class LessonIndex(BaseModel):
    lessons: list[LessonInfo]
    model: str = Field(description="the served model")
    models: list[str] = Field(description="every model the app can serve")
    modes: dict[str, str] = Field(description="training mode of each model (faithful, end_to_end, ...)")
    scenes: list[SceneChoice] = Field(description="corpus recordings, first variant of each scene")


class Pulse(BaseModel):
    tau: float
    input: list[float]
    z: list[float] = Field(description="internal state of the unit, eq. (3)")
    peak: float
    half_life_steps: float | None
    left_after_20_steps: float = Field(description="share of z left 20 steps after the pulse ends")
    references: dict[str, list[float]] = Field(
        description="the same pulse at MTRNN_a's IO, Cf, Cs timescales"
    )


class Layer(BaseModel):
    tau: float
    y: list[list[float]] = Field(description="[units][T] activations")
    speed: float = Field(description="mean |y_t - y_t-1|: how fast the layer's activity changes")


class Activity(BaseModel):
    id: str
    model: str
    expected: str
    said: str
    phonemes: list[str]
    steps: int
    phoneme_labels: list[str]
    phoneme_at: list[str] = Field(description="the phoneme the IO layer produces at each step ('' if none)")
    layers: dict[str, Layer]


class Speech(BaseModel):
    text: str
    phonemes: list[str]
    params: dict[str, float]
    lambda_: float = Field(alias="lambda", description="eq. (20)")
    steps: int
    labels: list[str] = Field(description="the neurons of B the sentence uses")
    spikes: list[list[float]] = Field(description="[used neurons][T] Gaussian spikes g, eqs. (18)-(19)")
    activity: list[list[float]] = Field(description="[used neurons][T] softmax activity y*, eq. (21)")
    peak: float
    decoded: list[str]
    read_back: str
    exact: bool


class Stage(BaseModel):
    key: str
    title: str
    image: str = Field(description="data URL: PNG for masks and edges, JPEG for colour pictures")


class Seen(BaseModel):
    width: int
    height: int
    found: bool
    pipeline_ms: float
    stages: list[Stage]
    features: list[float]
    feature_names: list[str]
    paper_features: int
    source: str = Field("", description="where the picture came from")
    frames: int = Field(0, description="frames of the recording (0 for an upload)")


class Feeling(BaseModel):
    action: str
    colour: str
    joint_names: list[str]
    series: list[dict[str, Any]]
    comparison: dict[str, Any] | None


class CosineStart(BaseModel):
    psi: float = Field(ge=0.0, le=0.01, description="self-organisation forcing (eqs. 11-12)")
    seed: int = Field(0, ge=0, le=10_000)


class CosineRun(BaseModel):
    id: str
    psi: float
    seed: int
    status: Literal["queued", "running", "done", "failed"]
    epoch: int
    epochs: int
    progress: float
    loss: float | None
    frames: list[dict[str, Any]] = Field(description="Csc points (and d_avg, d_rel) over training")
    frame_count: int
    result: dict[str, Any] | None
    error: str | None
    seconds: float


class Association(BaseModel):
    id: str
    model: str
    mute: str
    expected: str
    said: str
    unmuted: str
    slots: dict[str, dict[str, str | None]]
    index: int
    point_a: list[float]
    moved: float = Field(description="how far c_a,0 moved in the auditory Csc space by muting")
    nearest: dict[str, str]
    labels: list[dict[str, str]]
    spaces: dict[str, dict[str, list[float]]]


class Generalisation(BaseModel):
    model: str
    mode: str
    actions: list[str]
    objects: list[str]
    scenes: list[dict[str, Any]]
    train: dict[str, Any]
    test: dict[str, Any]
    test_object_seen: dict[str, Any]
    test_object_unseen: dict[str, Any]


# --- endpoints --------------------------------------------------------------------------------


@router.get("", response_model=LessonIndex)
def index(store: LessonsDep) -> LessonIndex:
    """The lessons, the models and one recording per scene to choose from."""
    lm_split = _call(store.model)
    firsts: dict[str, Any] = {}
    for e in store.state.entries.values():
        if e.scene.id not in firsts or e.variant < firsts[e.scene.id].variant:
            firsts[e.scene.id] = e
    return LessonIndex(
        lessons=[LessonInfo(id=i, title=t) for i, t in L.LESSONS],
        model=store.served,
        models=store.model_names(),
        modes=store.model_modes(),
        scenes=[
            SceneChoice(id=e.id, utterance=e.utterance, split=lm_split.split_of(e.id, e.scene.id))
            for e in firsts.values()
        ],
    )


@router.get("/timescales/pulse", response_model=Pulse, responses=ERRORS)
def pulse(tau: Annotated[float, Query(description="timescale of the unit (1..200)")]) -> Pulse:
    """Lesson 1: one leaky integrator (eq. 3) answering a 10-step pulse."""
    return Pulse(**_call(L.leaky_pulse, tau))


@router.get("/timescales/activity", response_model=Activity, responses=ERRORS)
def activity(store: LessonsDep, scene: Annotated[str, Query(description="recording id")]) -> Activity:
    """Lesson 1: MTRNN_a's IO, Cf and Cs activity while describing one recording."""
    return Activity(**_call(L.timescale_activity, store, scene))


@router.get("/speaking", response_model=Speech, responses=ERRORS, response_model_by_alias=True)
def speaking(
    store: LessonsDep,
    text: Annotated[str, Query(description="a sentence of words the CMU dictionary knows")],
    gamma: Annotated[int, Query(description="head margin, eq. (19)")] = 4,
    omega: Annotated[int, Query(description="filter width, even")] = 4,
    sigma2: Annotated[float, Query(description="sigma^2, filter sharpness, eq. (18)")] = 0.3,
    nu: Annotated[int, Query(description="steps between two phonemes")] = 2,
) -> Speech:
    """Lesson 2: text -> phonemes -> spikes -> softmax (eqs. 18-21) -> decoder."""
    return Speech(**_call(L.speak, text, gamma, omega, sigma2, nu, store.corpus_lexicon))


@router.get("/seeing", response_model=Seen, responses=ERRORS)
def seeing(
    store: LessonsDep,
    scene: Annotated[str, Query(description="recording id")],
    frame: Annotated[int, Query(description="frame index")] = 0,
    colour_radius: Annotated[int, Query(description="mean-shift colour window (4..64)")] = 24,
) -> Seen:
    """Lesson 3: the vision pipeline (Fig. 7) on one frame of a corpus recording."""
    _call(store.entry, scene)
    frames = store.state.frames(scene)
    if not 0 <= frame < len(frames):
        raise HTTPException(422, f"{scene} has frames 0..{len(frames) - 1}, not {frame}")
    out = _call(L.seeing, frames[frame], colour_radius)
    return Seen(**out, source=f"{scene}, frame {frame}", frames=len(frames))


@router.post("/seeing", response_model=Seen, responses=ERRORS)
async def seeing_upload(
    store: LessonsDep,
    image: Annotated[UploadFile, File(description="a PNG or JPEG picture")],
    colour_radius: Annotated[int, Query(description="mean-shift colour window (4..64)")] = 24,
) -> Seen:
    """Lesson 3: the vision pipeline on an uploaded picture."""
    data = await image.read(MAX_IMAGE_BYTES + 1)
    if len(data) > MAX_IMAGE_BYTES:
        raise HTTPException(413, f"the picture is larger than {MAX_IMAGE_BYTES // (1024 * 1024)} MB")
    frame = _call(L.decode_image, data)
    out = _call(L.seeing, frame, colour_radius)
    return Seen(**out, source=image.filename or "upload")


@router.get("/feeling", response_model=Feeling, responses=ERRORS)
def feeling(
    store: LessonsDep,
    action: Annotated[str, Query(description="pull, push, show me or slide")] = "push",
    colour: Annotated[str, Query(description="blue, green, red or yellow")] = "red",
) -> Feeling:
    """Lesson 4: one action on the four shapes, and why touch alone cannot tell objects apart."""
    return Feeling(**_call(L.feeling, store, action.replace("-", " "), colour))


@router.post("/abstracting/runs", response_model=CosineRun, responses=ERRORS, status_code=202)
def start_cosine(store: LessonsDep, body: CosineStart) -> CosineRun:
    """Lesson 5: start the cosine experiment (3.2.2) for one psi; poll the run for its progress."""
    job = _call(store.cosine.start, body.psi, body.seed)
    return CosineRun(**job.public())


@router.get("/abstracting/runs/{run_id}", response_model=CosineRun, responses=ERRORS)
def cosine_run(
    store: LessonsDep,
    run_id: str,
    since: Annotated[int, Query(ge=0, description="only the Csc frames from this index on")] = 0,
) -> CosineRun:
    """Lesson 5: progress of a cosine run, with the Csc points recorded so far."""
    return CosineRun(**_call(store.cosine.get, run_id).public(since))


class Sweeps(BaseModel):
    available: bool = Field(description="whether a psi_s sweep is stored")
    reason: str = Field(description="why not, when it is not")
    psi_s: list[dict[str, Any]] = Field(
        description="per psi_s: Fig. 9 measures, mean and *_sem (model.experiments.sweeps)"
    )
    cosine: list[dict[str, Any]] = Field(
        description="per psi: Fig. 3 (a, b) measures of the stored cosine sweep"
    )


@router.get("/abstracting/sweep", response_model=Sweeps)
def sweep() -> Sweeps:
    """Lesson 5: the stored psi_s and cosine sweeps of the protocol's run store ($MTRNN_RUN_DIR)."""
    return Sweeps(**L.stored_sweeps(default_run_dir()))


@router.get("/associating", response_model=Association, responses=ERRORS)
def associating(
    store: LessonsDep,
    scene: Annotated[str, Query(description="recording id")],
    mute: Annotated[str, Query(description="none, vision or proprioception")] = "none",
) -> Association:
    """Lesson 6: the three Csc spaces (Fig. 10) and what the model says with one sense muted."""
    return Association(**_call(L.associating, store, scene, mute))


@router.get("/generalising", response_model=Generalisation, responses=ERRORS)
def generalising(
    store: LessonsDep,
    model: Annotated[str | None, Query(description="model name (default: the served one)")] = None,
) -> Generalisation:
    """Lesson 7: training vs novel scenes for one model."""
    return Generalisation(**_call(L.generalising, store, model))
