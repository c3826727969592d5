"""Config-driven studies: TOML schema, runner, result store, reference cache, summary."""

from jaxrender.errors import StudyError, Unavailable, UserError  # noqa: F401
from jaxrender.study.runner import RunResult, run_study  # noqa: F401
from jaxrender.study.schema import load_study  # noqa: F401
from jaxrender.study.specs import FIGURES, Study  # noqa: F401
