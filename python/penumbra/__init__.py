"""penumbra: soft shadows from area lights, measured against a ray-traced reference.

    import penumbra
    scene = penumbra.load_scene("torus")             # a built-in scene, or a JSON scene file
    gbuffer = penumbra.render_gbuffer(scene, 256, 256)
    v = penumbra.visibility("pcss", scene, gbuffer, map_size=512)
    reference = penumbra.Technique("reference", spp=64)
    reference.prepare(scene)
    truth = reference.visibility(gbuffer)
    penumbra.compare_visibility(v, truth, penumbra.error_mask(gbuffer, scene))["rmse8"]

Arrays are numpy: V and masks (height, width), images and G-buffer fields (height, width, 3).
Bad input raises penumbra.Error with the message the command-line tool prints.
"""
import json
import os

from ._penumbra import (Error, GBuffer, Scene, Technique, __version__, cli, compare_visibility, error_mask,
                        load_scene, make_gbuffer, render_gbuffer, scenes, shade, techniques)

__all__ = ["Error", "GBuffer", "Scene", "Technique", "__version__", "cli", "compare", "compare_visibility",
           "error_mask", "load_scene", "make_gbuffer", "render_gbuffer", "scenes", "shade", "techniques", "visibility"]


def visibility(technique, scene, gbuffer, light=0, **params):
    """V of one technique (a name of techniques()) with its parameters, for light `light` of the scene."""
    t = Technique(technique, **params)
    t.prepare(scene, light)
    return t.visibility(gbuffer)


def compare(scene, techniques=None, out="out", width=None, height=None, spp=None, light=0, params=None,
            cache_dir=None):
    """Runs `penumbra compare` in this process and returns its compare.json as a dict.

    `scene` is a built-in name, a scene file or a loaded Scene; `techniques` one name or a list.

    The report (index.html, compare.md, compare.json, images) goes to OUT/report, as the command
    writes it; `params` maps "technique.key" (or "*.key") to a value. A technique named in
    `techniques` that cannot run on the scene keeps its row with the reason, and the exit status the
    command would return is in the result as "exit_status".
    """
    if isinstance(scene, Scene):  # the name it was loaded by: a built-in's, or its file
        scene = scene.name if scene.source.startswith("built-in:") else scene.source
    if isinstance(techniques, str):
        techniques = [techniques]
    args = ["compare", "--scene", str(scene), "--out", str(out), "--light", str(light)]
    if techniques:
        args += ["--techniques", ",".join(techniques)]
    if width is not None:
        args += ["--width", str(width)]
    if height is not None:
        args += ["--height", str(height)]
    if spp is not None:
        args += ["--spp", str(spp)]
    if cache_dir is not None:
        args += ["--cache-dir", str(cache_dir)]
    for key, value in (params or {}).items():
        if isinstance(value, bool):
            value = "true" if value else "false"
        args += ["--param", f"{key}={value}"]
    status = cli(args)
    with open(os.path.join(str(out), "report", "compare.json"), encoding="utf-8") as f:
        result = json.load(f)
    result["exit_status"] = status
    return result
