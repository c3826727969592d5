"""The reference cache: keys follow what the reference depends on; writes are atomic."""

import numpy as np

from jaxrender.scene.camera import look_at
from jaxrender.study import cache, references
from jaxrender.study.specs import ReferenceSpec, SceneSpec

SCENE = SceneSpec("tiny", "tiny", (("n", 2),))
REF = ReferenceSpec("reference", (("samples", 4),))
CAM = look_at((0, 0.5, 3), (0, 0, 0))


def test_key_depends_on_inputs():
    k = cache.reference_key(SCENE, CAM, REF, (24, 16))
    assert k == cache.reference_key(SCENE, look_at((0, 0.5, 3), (0, 0, 0)), REF, (24, 16))
    others = [
        cache.reference_key(SceneSpec("tiny", "tiny", (("n", 3),)), CAM, REF, (24, 16)),
        cache.reference_key(SCENE, look_at((0.01, 0.5, 3), (0, 0, 0)), REF, (24, 16)),
        cache.reference_key(SCENE, CAM, ReferenceSpec("reference", (("samples", 8),)), (24, 16)),
        cache.reference_key(SCENE, CAM, REF, (24, 18)),
        cache.reference_key(SceneSpec("tiny", "tiny", (("n", 2),), "abc"), CAM, REF, (24, 16)),
    ]
    assert len({k, *others}) == 6


def test_code_version_names_package_and_sources():
    import jaxrender

    v = cache.code_version()
    assert v.startswith(jaxrender.__version__ + "+") and len(v.split("+")[1]) == 12


def test_save_load_clear(tmp_path, monkeypatch):
    monkeypatch.setenv("JAXRENDER_CACHE", str(tmp_path))
    assert cache.cache_dir() == tmp_path / "reference"
    img = np.random.default_rng(0).random((4, 5, 3)).astype(np.float32)
    cache.save("k1", {"image": img})
    assert not list(cache.cache_dir().glob(".*"))  # no temporary left behind
    np.testing.assert_array_equal(cache.load("k1")["image"], img)
    (cache.cache_dir() / "bad.npz").write_bytes(b"not a zip")
    assert cache.load("bad") is None and cache.load("missing") is None
    assert cache.info()["entries"] == 2
    assert cache.clear() == 2 and cache.load("k1") is None


def test_rebuild_rerenders(fake, tiny_study, monkeypatch):
    from jaxrender.study.schema import load_study

    saved = []
    real = cache.save
    monkeypatch.setattr(cache, "save", lambda key, arrays: saved.append(key) or real(key, arrays))
    study = load_study(tiny_study)
    assert references.rebuild(study, log=lambda m: None) == 6
    assert len(set(saved)) == 6 and len(list(cache.cache_dir().glob("*.npz"))) == 6
    references.rebuild(study, log=lambda m: None)
    assert len(saved) == 12 and set(saved[6:]) == set(saved[:6])  # every frame re-rendered
