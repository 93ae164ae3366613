"""The app's services, created once in the lifespan and handed to the routes as typed dependencies.

`Services` holds the corpus, the one model registry, the one Csc survey, the describe service, the
timelines (the live description), the one job manager and (when running) the 3D views. A route
asks for what it uses: ``def route(models: ModelsDep, survey: SurveyDep) -> ...``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

from fastapi import Depends, Request
from starlette.requests import HTTPConnection

from server.jobs.manager import JobManager
from server.services.corpus import Corpus
from server.services.describe import DescribeService
from server.services.examples import ExampleService
from server.services.models import ModelRegistry
from server.services.survey import SurveyService
from server.services.timeline import TimelineService
from server.settings import Settings

if TYPE_CHECKING:
    from server.viewer import ViewerPool


@dataclass
class Services:
    settings: Settings
    corpus: Corpus
    models: ModelRegistry
    survey: SurveyService
    describe: DescribeService
    timeline: TimelineService
    jobs: JobManager
    examples: ExampleService
    viewer: ViewerPool | None = None  # the 3D views, one per page load


def build_services(settings: Settings, corpus: Corpus) -> Services:
    """Every service of one app over `corpus`; a finished training job's model joins the registry."""
    models = ModelRegistry.serving(settings, corpus)
    describe = DescribeService(corpus, models, settings.upload_cache, settings.decode_slots)
    return Services(
        settings=settings,
        corpus=corpus,
        models=models,
        survey=SurveyService(corpus, models),
        describe=describe,
        timeline=TimelineService(corpus, models, describe),
        jobs=JobManager(settings, on_model=models.register),
        examples=ExampleService(settings.user_dir),
    )


def services_of(conn: HTTPConnection) -> Services:
    """The services of the app serving this request (or WebSocket)."""
    return conn.app.state.services


def get_services(request: Request) -> Services:
    return services_of(request)


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_corpus(request: Request) -> Corpus:
    return services_of(request).corpus


def get_models(request: Request) -> ModelRegistry:
    return services_of(request).models


def get_survey(request: Request) -> SurveyService:
    return services_of(request).survey


def get_describe(request: Request) -> DescribeService:
    return services_of(request).describe


def get_timeline(request: Request) -> TimelineService:
    return services_of(request).timeline


def get_examples(request: Request) -> ExampleService:
    return services_of(request).examples


def get_jobs(request: Request) -> JobManager:
    return request.app.state.jobs


ServicesDep = Annotated[Services, Depends(get_services)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
CorpusDep = Annotated[Corpus, Depends(get_corpus)]
ModelsDep = Annotated[ModelRegistry, Depends(get_models)]
SurveyDep = Annotated[SurveyService, Depends(get_survey)]
DescribeDep = Annotated[DescribeService, Depends(get_describe)]
TimelineDep = Annotated[TimelineService, Depends(get_timeline)]
JobsDep = Annotated[JobManager, Depends(get_jobs)]
ExamplesDep = Annotated[ExampleService, Depends(get_examples)]
