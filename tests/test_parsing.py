"""The one reader of typed-in text: resolutions, key=value settings and name:key=value specs."""

import argparse

import pytest

from jaxrender.errors import UserError
from jaxrender.parsing import (MAX_SIDE, help_summary, parse_resolution, parse_setting,
                               parse_settings, parse_spec, resolution_arg)


@pytest.mark.parametrize("bad", ["64", "64x", "x48", "64x48x2", "-4x4", "0x4", "4.5x4",
                                 f"{MAX_SIDE + 1}x4", [64], [64, "48"], [True, 4], 64])
def test_resolution_errors_name_where_and_the_value(bad):
    with pytest.raises(UserError, match=r"^--size: expected 'WxH'") as e:
        parse_resolution(bad, "--size")
    assert str(e.value).endswith((f"got {bad!r}", f"got {bad}")), str(e.value)


def test_resolution_arg_for_argparse():
    assert resolution_arg("1920X1080") == (1920, 1080)
    p = argparse.ArgumentParser(exit_on_error=False)
    p.add_argument("--resolution", type=resolution_arg)
    with pytest.raises(argparse.ArgumentError, match="--resolution: expected 'WxH'.*'12'"):
        p.parse_args(["--resolution", "12"])


def test_settings_take_toml_values_and_bare_words():
    assert parse_settings(["a=4", "b = 0.5", "c=true", "d=[1, 2]", 'e="x y"', "f= word ",
                           "a=5"], "--set") == {"a": 5, "b": 0.5, "c": True, "d": [1, 2],
                                               "e": "x y", "f": "word"}
    for bad in ("levels", "=4"):
        with pytest.raises(UserError, match=f"^--set '{bad}': expected key=value"):
            parse_setting(bad, "--set")


def test_spec_splits_name_and_settings():
    assert parse_spec("many_small:n_triangles=1000,point_lights=4") == (
        "many_small", {"n_triangles": 1000, "point_lights": 4})
    assert parse_spec(" forward ") == ("forward", {})
    with pytest.raises(UserError, match="scene 'x:n': 'n': expected key=value"):
        parse_spec("x:n", "scene")


def test_help_summary_is_the_docstrings_first_paragraph_on_one_line():
    doc = """Frame time against shading work: every pipeline on a few scenes, and
    each pipeline's fixed cost.

        python benchmarks/bench_time_work.py --scenes foliage
    """
    assert help_summary(doc) == ("Frame time against shading work: every pipeline on a few "
                                 "scenes, and each pipeline's fixed cost.")
    assert help_summary("One line.") == "One line."
    assert help_summary(None) == ""
