"""volvis.open(..., slices=(first, count)): a sub-stack of a TIFF stack written
by tifffile, against numpy's slices of the same array; refusals."""
import numpy as np
import pytest

import volvis

tifffile = pytest.importorskip("tifffile")


def test_tiff_sub_stack(tmp_path):
    z, y, x = np.mgrid[0:40, 0:23, 0:17]
    data = ((x * 7 + y * 31 + z * 101) % 60000).astype(np.uint16)
    path = tmp_path / "stack.tif"
    tifffile.imwrite(path, data, imagej=True, compression="zlib",
                     metadata={"spacing": 2.5, "unit": "um", "axes": "ZYX"})
    whole = volvis.open(path)
    part = volvis.open(path, slices=(11, 9))
    assert part.dims == (17, 23, 9)
    assert np.array_equal(part.array, data[11:20])
    assert part.origin[2] == pytest.approx(whole.origin[2] + 11 * 2.5)
    with pytest.raises(volvis.InvalidError, match="the stack has 40"):
        volvis.open(path, slices=(35, 6))
    with pytest.raises(volvis.InvalidError):
        volvis.open(path, slices=(-1, 3))


def test_slices_of_a_format_read_whole(tmp_path):
    vol = volvis.Volume(np.zeros((6, 5, 4), np.uint8))
    path = tmp_path / "v.nii"
    vol.save(path)
    with pytest.raises(volvis.UnsupportedError, match="v.nii"):
        volvis.open(path, slices=(1, 2))
