"""The Python module against independent evidence: the CLI's listings and compare.json, numpy's own
arithmetic, the README's table, and its error messages. Run by ctest ('python') with
PYTHONPATH=build/python, PENUMBRA_CLI (the program) and PENUMBRA_SOURCE_DIR set."""
import gc
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import penumbra

CLI = os.environ["PENUMBRA_CLI"]
SOURCE = pathlib.Path(os.environ["PENUMBRA_SOURCE_DIR"])


@pytest.fixture(scope="module")
def torus():
    scene = penumbra.load_scene("torus")
    return scene, penumbra.render_gbuffer(scene, 96, 96)


def cli_listing(command):
    return subprocess.run([CLI, command], check=True, capture_output=True, text=True).stdout


def test_scenes_and_techniques_are_the_clis():
    scenes = cli_listing("scenes")
    for s in penumbra.scenes():
        assert s["name"] in scenes and s["description"]
    techniques = cli_listing("techniques")
    listed = penumbra.techniques()
    assert [t["name"] for t in listed][:3] == ["reference", "none", "hard"]
    for t in listed:
        assert t["name"] in techniques
        for p in t["params"]:
            assert p["name"] in techniques
    pcss = next(t for t in listed if t["name"] == "pcss")
    map_size = next(p for p in pcss["params"] if p["name"] == "map_size")
    assert map_size["type"] == "int" and map_size["min"] == 16 and map_size["max"] == 8192 and map_size["unit"]


def test_gbuffer_fields_are_read_only_views(torus):
    scene, gbuffer = torus
    assert gbuffer.position.shape == (96, 96, 3) and gbuffer.position.dtype == np.float32
    assert gbuffer.object_id.shape == (96, 96) and gbuffer.object_id.dtype == np.int32
    assert gbuffer.depth.shape == (96, 96)
    for field in (gbuffer.position, gbuffer.normal, gbuffer.geometric_normal, gbuffer.object_id, gbuffer.depth):
        assert field.base is not None and not field.flags.writeable  # no copy, and not to be written
    hit = gbuffer.object_id >= 0
    assert 0 < hit.sum() < hit.size
    assert np.allclose(np.linalg.norm(gbuffer.normal[hit], axis=-1), 1.0, atol=1e-4)
    assert np.all(np.isinf(gbuffer.depth[~hit]))


def test_views_outlive_their_gbuffer_and_parameters_convert():
    scene = penumbra.load_scene("torus")
    gbuffer = penumbra.render_gbuffer(scene, 40, 30)
    position, expected = gbuffer.position, np.array(gbuffer.position)
    del gbuffer
    gc.collect()
    assert np.array_equal(position, expected)  # the view kept its G-buffer alive
    gbuffer = penumbra.render_gbuffer(scene, 40, 30)
    a = penumbra.visibility("pcss", scene, gbuffer, map_size=np.int64(256), light_size=None)  # numpy int, "auto"
    b = penumbra.visibility("pcss", scene, gbuffer, map_size=256)
    assert np.array_equal(a, b)
    c = penumbra.visibility("brabec", scene, gbuffer, coverage_bound=np.bool_(False), meet=np.float32(0.5))
    assert c.shape == (30, 40)
    with pytest.raises(penumbra.Error, match="map_size"):
        penumbra.Technique("pcss", map_size=3)  # refused when made, not at prepare


def test_your_own_gbuffer_arrays(torus):
    scene, own = torus
    # Arrays of your own renderer (here penumbra's, copied into plain numpy arrays): the same V.
    g = penumbra.make_gbuffer(scene, np.array(own.position), np.array(own.normal), np.array(own.object_id),
                              geometric_normal=np.array(own.geometric_normal))
    assert (g.width, g.height) == (96, 96)
    assert np.array_equal(penumbra.visibility("pcss", scene, g), penumbra.visibility("pcss", scene, own))
    with pytest.raises(penumbra.Error, match=r"position: expected shape \(96, 96, 3\)"):
        penumbra.make_gbuffer(scene, np.zeros((96, 95, 3)), np.array(own.normal), np.array(own.object_id))
    ids = np.array(own.object_id)
    ids[ids >= 0] = 77
    with pytest.raises(penumbra.Error, match="is 77: expected kNoObject"):
        penumbra.make_gbuffer(scene, np.array(own.position), np.array(own.normal), ids)


def test_rmse8_is_numpys_and_the_clis(torus, tmp_path):
    scene, gbuffer = torus
    v = penumbra.visibility("pcss", scene, gbuffer)
    assert v.shape == (96, 96) and v.dtype == np.float32 and v.min() >= 0.0 and v.max() <= 1.0
    reference = penumbra.Technique("reference", spp=64)
    reference.prepare(scene)
    truth = reference.visibility(gbuffer)
    assert reference.standard_error.shape == (96, 96)
    assert reference.stats()["rays"] > 0
    mask = penumbra.error_mask(gbuffer, scene)
    error = penumbra.compare_visibility(v, truth, mask)
    # The closed form, in numpy, over the same mask.
    d = (v.astype(np.float64) - truth)[mask == 1]
    assert error["rmse8"] == pytest.approx(np.sqrt(np.mean(d * d)) * 255.0, rel=1e-6)
    assert error["mask_pixels"] == int(mask.sum())
    # The command-line tool's compare on the same pixels and reference: the same RMSE8.
    result = penumbra.compare(scene, techniques="pcss", out=tmp_path, width=96, height=96, spp=64)
    assert result["exit_status"] == 0
    row = next(t for t in result["techniques"] if t["name"] == "pcss")
    assert row["rmse8"] == pytest.approx(error["rmse8"], abs=5e-3)
    for name in ("index.html", "compare.md", "compare.json"):
        assert (tmp_path / "report" / name).is_file()


def test_shade_and_determinism(torus):
    scene, gbuffer = torus
    a = penumbra.visibility("raytraced-soft", scene, gbuffer, seed=3)
    b = penumbra.visibility("raytraced-soft", scene, gbuffer, seed=3)
    assert np.array_equal(a, b)
    lit = penumbra.shade(scene, gbuffer, np.ones_like(a))
    shaded = penumbra.shade(scene, gbuffer, a)
    assert shaded.shape == (96, 96, 3) and shaded.dtype == np.float32
    hit = gbuffer.object_id >= 0
    assert np.all(shaded[hit] <= lit[hit] + 1e-6)  # a shadow only darkens


def test_errors_carry_the_clis_messages(torus):
    scene, gbuffer = torus
    with pytest.raises(penumbra.Error, match="no-such-scene: neither a built-in scene"):
        penumbra.load_scene("no-such-scene")
    with pytest.raises(penumbra.Error, match=r"pcss.map_size = 3 is not valid: expected int in \[16, 8192\]"):
        penumbra.Technique("pcss", map_size=3)
    with pytest.raises(penumbra.Error, match="unknown technique|not a technique|no technique"):
        penumbra.Technique("no-such-technique")
    with pytest.raises(penumbra.Error, match="light 5 does not exist"):
        penumbra.Technique("hard").prepare(scene, 5)
    with pytest.raises(penumbra.Error, match="one shape"):
        penumbra.compare_visibility(np.zeros((4, 4), np.float32), np.zeros((4, 5), np.float32),
                                    np.ones((4, 4), np.uint8))
    with pytest.raises(penumbra.Error, match="see penumbra --help"):
        penumbra.cli(["compare", "--no-such-option"])
    assert penumbra.cli(["scenes"]) == 0


def test_example_reproduces_the_readme_table():
    script = SOURCE / "examples" / "python" / "brabec_seidel_table.py"
    out = subprocess.run([sys.executable, str(script)], check=True, capture_output=True, text=True,
                         env=dict(os.environ)).stdout
    readme = (SOURCE / "README.md").read_text(encoding="utf-8")
    rows = [line for line in out.splitlines() if line.startswith("| ") and "[1]" in line]
    assert len(rows) == 6
    for line in rows:
        assert line in readme, f"not in the README: {line}"
