"""Every error path raises volvis.Error with the library's message."""
import numpy as np
import pytest

import volvis
from conftest import DATA


def test_truncated_file(tmp_path):
    raw = (DATA / "volumes" / "nut.slc").read_bytes()
    bad = tmp_path / "nut_truncated.slc"
    bad.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(volvis.Error) as e:
        volvis.open(bad)
    assert isinstance(e.value, (volvis.FormatError, volvis.FileError))
    assert "nut_truncated.slc" in str(e.value)
    assert e.value.status < 0 and e.value.status_name.startswith("VV_ERR_")


def test_missing_file(tmp_path):
    with pytest.raises(volvis.FileError) as e:
        volvis.open(tmp_path / "nothing.nrrd")
    assert "nothing.nrrd" in str(e.value)
    assert isinstance(e.value, OSError)


def test_bad_scene(tmp_path):
    scene = tmp_path / "bad.json"
    scene.write_text('{\n  "view": {"fov": "wide"}\n}\n')
    with pytest.raises(volvis.FormatError) as e:
        volvis.load_scene(scene)
    msg = str(e.value)
    assert "bad.json:2:" in msg and "view.fov" in msg and "number" in msg


def test_bad_option_name(ct_head):
    with pytest.raises(volvis.InvalidError) as e:
        volvis.render(ct_head, size=(16, 16), no_such_option=1)
    assert "no_such_option" in str(e.value)


def test_bad_option_value():
    with pytest.raises(volvis.InvalidError) as e:
        volvis.Renderer("raytrace", max_depth="lots")
    assert "max_depth" in str(e.value)


def test_unknown_renderer(ct_head):
    with pytest.raises(volvis.InvalidError) as e:
        volvis.render(ct_head, renderer="teapot")
    assert "teapot" in str(e.value) and "raycast" in str(e.value)


def test_wrong_dtype():
    with pytest.raises(volvis.InvalidError) as e:
        volvis.Volume(np.zeros((4, 4, 4), np.int64))
    assert "int64" in str(e.value) and "u8" in str(e.value)
    with pytest.raises(volvis.InvalidError):
        volvis.Volume(np.zeros((4, 4, 4), np.complex64))


def test_non_contiguous_array():
    a = np.zeros((8, 8, 8), np.float32)
    with pytest.raises(volvis.InvalidError) as e:
        volvis.Volume(a[:, ::2, :])
    assert "strides" in str(e.value) and "copy=True" in str(e.value)
    v = volvis.Volume(a[:, ::2, :], copy=True)
    assert v.dims == (8, 4, 8) and not v.shares_memory


def test_bad_arguments():
    with pytest.raises(volvis.InvalidError):
        volvis.Volume(np.zeros((4, 4), np.uint8), spacing=(1, 0, 1))
    with pytest.raises(volvis.InvalidError):
        volvis.View(fov=200)
    with pytest.raises(volvis.InvalidError) as e:
        volvis.TransferFunction(opacity=[(0, 2.0)])
    assert "opacity" in str(e.value)
    with pytest.raises(volvis.LimitError):
        volvis.Volume(np.zeros((2, 2, 70000), np.uint8))
    with pytest.raises(volvis.InvalidError):
        volvis.render(np.zeros((4, 4, 4), np.uint8), size=(0, 10))
    with pytest.raises(volvis.InvalidError):
        volvis.filter(np.zeros((4, 4, 4), np.uint8), median=-3)
    with pytest.raises(volvis.InvalidError):
        volvis.TransferFunction.preset("no-such-preset")
