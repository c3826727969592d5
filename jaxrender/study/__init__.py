"""Config-driven studies: TOML schema, runner, result store, reference cache and timing."""

from jaxrender.study.errors import StudyError, Unavailable, UserError  # noqa: F401
from jaxrender.study.schema import Study, load_study, parse_resolution  # noqa: F401


def run_study(*args, **kwargs):
    """See ``jaxrender.study.runner.run_study``."""
    from jaxrender.study.runner import run_study as run

    return run(*args, **kwargs)
