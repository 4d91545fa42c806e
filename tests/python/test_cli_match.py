"""The Python render of a scene equals `volvis render` of the same scene bit for bit."""
import subprocess

import numpy as np
import pytest

import volvis
from conftest import DATA, ROOT, cli


@pytest.mark.parametrize("scene,args", [
    ("ct_head.json", []),
    ("head_mirror.json", ["--renderer", "raytrace", "--quality", "0"]),
])
def test_python_render_equals_cli(tmp_path, scene, args):
    exe = cli()
    assert exe, "the volvis CLI of this build was not found"
    png = tmp_path / "cli.png"
    size = ["--size", "160x120"]
    subprocess.run([exe, "render", str(ROOT / "examples" / scene), "-o", str(png)] + size + args,
                   check=True, cwd=ROOT)
    world = volvis.load_scene(ROOT / "examples" / scene)
    kw = {}
    if "--renderer" in args:
        kw["renderer"] = args[args.index("--renderer") + 1]
    if "--quality" in args:
        kw["quality"] = int(args[args.index("--quality") + 1])
    img = volvis.render(world, size=(160, 120), alpha=False, **kw)
    ref = volvis.read_png(png)
    assert img.shape == (120, 160, 3)
    np.testing.assert_array_equal(img, ref[..., :3])


def test_python_render_of_a_volume_equals_cli_default_scene(tmp_path, ct_head):
    exe = cli()
    png = tmp_path / "cli.png"
    subprocess.run([exe, "render", str(DATA / "volumes" / "ct_head.nrrd"), "-o", str(png),
                    "--size", "128x128", "--mode", "mip", "--azimuth", "30"], check=True)
    world = volvis.World.for_volume(ct_head, mode="mip", size=(128, 128), azimuth=30)
    np.testing.assert_array_equal(volvis.render(world, alpha=False),
                                  volvis.read_png(png)[..., :3])
