"""Reproduces the README's "Results in one table" rows of the Brabec-Seidel setup from Python:
`torus` at 512 x 512, light maps of 256 x 256, RMSE8 against the reference at 1024 rays per pixel,
each technique as its paper has it (horizon off: no clamp to the receiver's own horizon).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/brabec_seidel_table.py

The same numbers as `penumbra compare --scene torus --width 512 --height 512 --spp 1024 ...` (the
README's note [1]); prints the rows as the README's table has them.
"""
import argparse

import penumbra

ROWS = [  # (technique, README label)
    ("none", "none"),
    ("hard", "hard"),
    ("pcf", "pcf (3×3)"),
    ("pcss", "pcss (16 + 32 taps)"),
    ("multisample", "multisample (16)"),
    ("brabec", "brabec"),
]
MAPPED = {"hard", "pcf", "pcss", "multisample", "brabec"}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=512, help="image width and height (pixels)")
    parser.add_argument("--map-size", type=int, default=256, help="light map size of the shadow-map techniques")
    parser.add_argument("--spp", type=int, default=1024, help="the reference's rays per pixel")
    args = parser.parse_args()

    scene = penumbra.load_scene("torus")
    gbuffer = penumbra.render_gbuffer(scene, args.size, args.size)
    mask = penumbra.error_mask(gbuffer, scene)
    reference = penumbra.Technique("reference", spp=args.spp)
    reference.prepare(scene)
    truth = reference.visibility(gbuffer)

    def rmse8(name, **params):
        v = penumbra.visibility(name, scene, gbuffer, **params)
        return penumbra.compare_visibility(v, truth, mask)["rmse8"]

    exact = rmse8("raytraced-hard")
    setup = f"`torus`, {args.size}², {args.map_size}² maps [1]"
    print("| technique | scene and setup | RMSE8 | raytraced-hard there |")
    print("|---|---|---|---|")
    for name, label in ROWS:
        params = {"map_size": args.map_size, "horizon": "off"} if name in MAPPED else {}
        print(f"| {label} | {setup} | {rmse8(name, **params):.2f} | {exact:.2f} |")


if __name__ == "__main__":
    main()
