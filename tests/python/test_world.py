"""The World in Python: objects, lights, cut planes, transfer functions, views
and scene files."""
import numpy as np
import pytest

import volvis
from conftest import ROOT


def test_build_save_load_render(tmp_path, rng):
    a = np.zeros((32, 32, 32), np.uint8)
    a[8:24, 8:24, 8:24] = rng.integers(100, 255, size=(16, 16, 16))
    w = volvis.World()
    vo = w.add(volvis.VolumeObject(volvis.Volume(a, spacing=(2, 2, 2)), name="cube"))
    vo.tf = volvis.TransferFunction.ramp(50, 255, 0.8, color=(1, 0.8, 0.6), unit_distance=2)
    vo.material = volvis.Material(ambient=0.2, diffuse=0.7, specular=0.1, shininess=10)
    vo.position = (-31, -31, -31)
    vo.rotate((0, 0, 1), 20)
    vo.cut_planes = [((0, 0, 0), (1, 0, 0))]
    s = w.add(volvis.Sphere(center=(0, 0, 50), radius=10, name="ball"))
    s.material.color = (1, 0, 0)
    w.add_light(direction=(0, 1, -1), color=(1, 1, 0.9), intensity=0.8)
    w.add_light()  # a headlight
    w.add_cut_plane((0, 0, -20), (0, 0, 1))
    w.background = (0.1, 0.1, 0.2)
    w.view = volvis.View(eye=(0, -300, 100), at=(0, 0, 0), up=(0, 0, 1), fov=35, size=(96, 80))
    w.renderer, w.quality = "raytrace", 0
    w.set_render_option("shadows", True)
    assert w.render_options == {"shadows": "1"}
    assert [o.name for o in w.objects] == ["cube", "ball"] and w.objects["ball"] is s
    img = volvis.render(w)
    assert img.shape == (80, 96, 4)
    path = tmp_path / "scene.json"
    with pytest.raises(volvis.InvalidError):
        w.save(path)  # the numpy volume has no file yet
    w.save(path, write_volumes=True)
    back = volvis.load_scene(path)
    assert back.renderer == "raytrace" and back.quality == 0
    assert len(back.lights) == 2 and back.lights[1].headlight
    assert back.objects[0].tf.opacity.tolist() == vo.tf.opacity.tolist()
    assert back.view.fov == pytest.approx(35)
    np.testing.assert_array_equal(volvis.render(back), img)


def test_proxies_write_through_and_clone(ct_head):
    w = volvis.World.for_volume(ct_head, size=(64, 64))
    before = volvis.render(w)
    snap = w.clone()
    w.view.orbit(azimuth=90)
    assert not np.array_equal(volvis.render(w), before)
    np.testing.assert_array_equal(volvis.render(snap), before)
    o = w.objects[0]
    o.visible = False
    assert volvis.render(w)[..., 3].max() == 0
    removed = w.remove(0)
    assert len(w.objects) == 0 and removed.name
    w.add(removed)
    assert w.objects[0] is removed


def test_transfer_functions(ct_head):
    tf = volvis.TransferFunction.from_array([0, 100, 200], [[0, 0, 0, 0], [1, 0, 0, 0.5],
                                                            [1, 1, 1, 1]])
    np.testing.assert_allclose(tf([50, 150]), [[0.5, 0, 0, 0.25], [1, 0.5, 0.5, 0.75]])
    assert "ct-bone" in volvis.tf_presets()
    bone = volvis.TransferFunction.preset("ct-bone", ct_head)
    assert len(bone.opacity) >= 2
    t2 = volvis.TransferFunction2D().add_rectangle((0, 100), (0, 50), color=(1, 0, 0))
    assert t2(50, 25)[0] == pytest.approx(1.0) and t2.widgets[0]["shape"] == "rectangle"


def test_renderer_registry_help():
    assert set(volvis.renderers) >= {"raycast", "raytrace", "splat", "raster"}
    info = volvis.renderers["raytrace"]
    assert "shadows" in info.__doc__ and info.description
    # the typed option table: every default is accepted by the renderer
    assert info.options["shadows"]["type"] == "bool" and info.options["samples"]["max"] == 16
    assert "region" in info.capabilities and "volume" in info.draws
    for name, ri in volvis.renderers.items():
        for key, opt in ri.options.items():
            if opt["type"] != "string":
                volvis.Renderer(name).set(**{key: opt["default"]})
    r = info(shadows=False)
    assert isinstance(r, volvis.Renderer) and r.name == "raytrace"


def test_render_gpu(ct_head):
    """renderer="gpu" (the Vulkan ray caster; lavapipe in CI) gives the same
    uint8 image as raycast without refinement, to a step of rounding, napari's
    attenuated MIP too (no longer refused by the gpu)."""
    assert "gpu" in volvis.renderers
    for mode in ("composite", "mip", "attenuated-mip"):
        a = volvis.render(ct_head, renderer="gpu", mode=mode, size=(64, 48))
        b = volvis.render(ct_head, renderer="raycast", mode=mode, size=(64, 48),
                          refinement="off")
        assert a.shape == b.shape == (48, 64, 4)
        assert np.abs(a.astype(int) - b.astype(int)).max() <= 2
        assert a[..., :3].max() > 40  # something drawn


def test_jupyter_png(ct_head):
    img = volvis.render(ct_head, size=(40, 30))
    png = img._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    w = volvis.load_scene(ROOT / "examples" / "ct_head.json")
    w.view.size = (40, 30)
    assert w._repr_png_()[:4] == b"\x89PNG"
    shown = volvis.show(w, interactive=False)
    np.testing.assert_array_equal(shown, volvis.render(w))


def test_viewer_widget(ct_head):
    pytest.importorskip("ipywidgets")
    v = volvis.notebook.Viewer(volvis.World.for_volume(ct_head, size=(64, 64)))
    assert v.image.value[:4] == b"\x89PNG"
    v.azimuth.value = 40  # a drag: a preview now, the full image after refine_after
    assert v.image.value[:4] == b"\x89PNG" and v.status.value
    v.refine()
    turned = volvis.World.for_volume(ct_head, size=(64, 64), azimuth=40)
    assert v.image.value == volvis.notebook.png_bytes(volvis.render(turned))


def test_scene_time_step_round_trip(out_dir):
    """A volume object's "time" (issue 30): the scene draws that time step of
    an OME-TIFF written by tifffile, and saving the scene keeps it with the
    channels."""
    import json
    import tifffile
    rng = np.random.default_rng(3)
    data = rng.integers(0, 4000, size=(3, 2, 4, 9, 8), dtype=np.uint16)  # T, C, Z, Y, X
    tifffile.imwrite(str(out_dir / "cells.ome.tif"), data, metadata={"axes": "TCZYX"})
    scene = out_dir / "s.json"
    scene.write_text(json.dumps({"objects": [{
        "type": "volume", "file": "cells.ome.tif", "time": 2, "blend": "maximum",
        "channels": [{"channel": 1}, {"channel": 0}]}]}))
    w = volvis.load_scene(str(scene))
    obj = w.objects[0]
    np.testing.assert_array_equal(obj.volume.array, data[2, 1])
    again = out_dir / "again.json"
    w.save(str(again))
    saved = json.loads(again.read_text())["objects"][0]
    assert saved["time"] == 2
    assert [c["channel"] for c in saved["channels"]] == [1, 0]
    w2 = volvis.load_scene(str(again))
    np.testing.assert_array_equal(w2.objects[0].volume.array, data[2, 1])
