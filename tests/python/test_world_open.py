"""World.open, the library's one door (vv_world_open): a NIfTI file, a DICOM
folder written by pydicom, an OME-Zarr store written by `volvis convert`
and a scene file each open into the World `volvis render` draws, bit for
bit; what the door found (world.opened); the store in memory and out of
core; errors naming the input."""
import gc
import json
import subprocess

import numpy as np
import pytest

import volvis
from conftest import DATA, ROOT, cli

NIFTI = DATA / "volumes" / "avg152T1_RL_nifti.nii.gz"
CT = DATA / "volumes" / "ct_head.nrrd"
SCENE = ROOT / "examples" / "ct_head.json"


def cli_render(tmp_path, what, *args, name="cli.png"):
    """`volvis render WHAT ARGS` of this build, as an (h, w, 3) array."""
    exe = cli()
    assert exe, "the volvis CLI of this build was not found"
    png = tmp_path / name
    subprocess.run([exe, "render", str(what), "-o", str(png), "-q"] + [str(a) for a in args],
                   check=True, cwd=ROOT, capture_output=True)
    return volvis.read_png(png)[..., :3]


def opened_render(what, size, **kw):
    w = volvis.World.open(what, size=size, **kw)
    return w, volvis.render(w, alpha=False)


@pytest.mark.parametrize("path,args,kw", [
    (NIFTI, [], {}),
    (NIFTI, ["--mode", "mip"], {"mode": "mip"}),
    (NIFTI, ["--tf", "40:120", "--step", "1"], {"tf": (40, 120), "step": 1}),
])
def test_nifti_equals_cli(tmp_path, path, args, kw):
    w, img = opened_render(path, (96, 80), **kw)
    assert w.opened["input"] == "volume"
    assert (w.opened["n_channels"], w.opened["n_times"]) == (1, 1)
    assert not w.opened["out_of_core"] and not w.opened["switched"]
    assert w.opened["slice_window"] is None
    assert img.shape == (80, 96, 3) and img.any()
    np.testing.assert_array_equal(img, cli_render(tmp_path, path, "--size", "96x80", *args))


def test_overrides_change_the_world():
    plain = volvis.World.open(NIFTI, size=(64, 64))
    o = plain.objects[0]
    assert (o.mode, o.segmentation) == ("composite", "tf")
    w = volvis.World.open(NIFTI, mode="iso", iso=80, step=0.25, labels=True, size=(64, 48))
    o = w.objects[0]
    assert (o.mode, o.isovalue, o.step, o.segmentation) == ("iso", 80, 0.25, "labels")
    assert w.view.size == (64, 48)
    # the view is fitted the same way whatever the overrides
    np.testing.assert_allclose(w.view.at, plain.view.at)


def test_slice_window():
    w = volvis.World.open(NIFTI, slice_window=True)
    window, level = w.opened["slice_window"]
    lo, hi = w.objects[0].volume.range
    assert 0 < window <= hi - lo
    assert lo <= level <= hi
    assert volvis.World.open(NIFTI).opened["slice_window"] is None


# ---- a DICOM folder ------------------------------------------------------------------------
T, Z, Y, X = 3, 6, 20, 24


@pytest.fixture(scope="module")
def cine(tmp_path_factory):
    """A cine MR series by pydicom: T phases at each of Z positions, one
    image a file, written shuffled; phase t holds values around 1000 t."""
    pydicom = pytest.importorskip("pydicom")
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
    assert pydicom
    folder = tmp_path_factory.mktemp("cine")
    rng = np.random.default_rng(7)
    tzyx = np.zeros((T, Z, Y, X), dtype=np.uint16)
    zz, yy, xx = np.mgrid[:Z, :Y, :X]
    ball = ((zz - Z / 2) / Z) ** 2 + ((yy - Y / 2) / Y) ** 2 + ((xx - X / 2) / X) ** 2 < 0.16
    for t in range(T):
        tzyx[t] = rng.integers(0, 50, size=(Z, Y, X)) + ball * (1000 * (t + 1))
    mr = "1.2.840.10008.5.1.4.1.1.4"
    series, study, frame = generate_uid(), generate_uid(), generate_uid()
    for n, idx in enumerate(rng.permutation(T * Z)):
        t, z = int(idx % T), int(idx // T)
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = mr
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        path = folder / ("im%03d.dcm" % n)
        ds = FileDataset(str(path), {}, file_meta=meta, preamble=b"\0" * 128)
        ds.is_little_endian, ds.is_implicit_VR = True, False
        ds.SOPClassUID, ds.SOPInstanceUID = mr, meta.MediaStorageSOPInstanceUID
        ds.StudyInstanceUID, ds.SeriesInstanceUID = study, series
        ds.FrameOfReferenceUID, ds.Modality, ds.SeriesNumber = frame, "MR", 3
        ds.InstanceNumber = n + 1
        ds.TriggerTime = "%.1f" % (40 * t)
        ds.TemporalPositionIdentifier = t + 1
        ds.ImageOrientationPatient = ["1", "0", "0", "0", "1", "0"]
        ds.ImagePositionPatient = ["-15", "-12", "%.1f" % (2.0 * z)]
        ds.PixelSpacing = ["1.25", "1.25"]
        ds.SliceThickness = "2"
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.Rows, ds.Columns = Y, X
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
        ds.PixelData = tzyx[t, z].tobytes()
        ds.save_as(str(path), write_like_original=False)
    return folder, tzyx


def test_dicom_folder_equals_cli(tmp_path, cine):
    folder, tzyx = cine
    w, img = opened_render(folder, (72, 64), time=1, mode="mip")
    assert w.opened["input"] == "volume"
    assert (w.opened["n_channels"], w.opened["n_times"]) == (1, T)
    vol = w.objects[0].volume
    assert vol.array.shape == (Z, Y, X)
    assert vol.range[1] == tzyx[1].max()  # phase 1's voxels, not phase 0's
    assert img.any()
    np.testing.assert_array_equal(img, cli_render(tmp_path, folder, "--size", "72x64",
                                                  "--time", "1", "--mode", "mip"))
    # another phase is another image
    assert not np.array_equal(img, opened_render(folder, (72, 64), time=2, mode="mip")[1])


def test_dicom_time_past_the_series(cine):
    folder, _ = cine
    with pytest.raises(volvis.InvalidError) as e:
        volvis.World.open(folder, time=T)
    assert "\n" not in str(e.value)
    assert "time step %d" % T in str(e.value)


# ---- an OME-Zarr 0.5 store (Zarr v3, sharded) ------------------------------------------------
def _crc32c(data):
    crc = 0xFFFFFFFF
    for x in data:
        crc ^= x
        for _ in range(8):
            crc = (crc >> 1) ^ (0x82F63B78 & -(crc & 1))
    return crc ^ 0xFFFFFFFF


@pytest.fixture(scope="module")
def store_v3(tmp_path_factory):
    """A 32^3 u16 NGFF 0.5 image in one shard of 2 x 2 x 2 raw inner chunks (16^3, index at
    the end with its crc32c), written byte by byte as the Zarr v3 spec lays it out."""
    out = tmp_path_factory.mktemp("zarr3") / "v3.ome.zarr"
    arr = (np.arange(32 ** 3, dtype=np.uint32) * 7 % 4001).astype("<u2").reshape(32, 32, 32)
    body, index = b"", b""
    for k in range(2):
        for j in range(2):
            for i in range(2):
                inner = arr[16 * k:16 * k + 16, 16 * j:16 * j + 16, 16 * i:16 * i + 16].tobytes()
                index += np.array([len(body), len(inner)], "<u8").tobytes()
                body += inner
    shard = body + index + _crc32c(index).to_bytes(4, "little")
    (out / "0" / "c" / "0" / "0").mkdir(parents=True)
    (out / "0" / "c" / "0" / "0" / "0").write_bytes(shard)
    (out / "zarr.json").write_text(json.dumps({
        "zarr_format": 3, "node_type": "group", "attributes": {"ome": {
            "version": "0.5", "multiscales": [{
                "axes": [{"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"],
                "datasets": [{"path": "0", "coordinateTransformations": [
                    {"type": "scale", "scale": [2.0, 1.0, 0.5]}]}]}]}}}))
    (out / "0" / "zarr.json").write_text(json.dumps({
        "zarr_format": 3, "node_type": "array", "shape": [32, 32, 32], "data_type": "uint16",
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [32, 32, 32]}},
        "chunk_key_encoding": {"name": "default"}, "fill_value": 0,
        "codecs": [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [16, 16, 16],
            "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}],
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                             {"name": "crc32c"}]}}]}))
    return out, arr


def test_store_v3_sharded(store_v3):
    path, arr = store_v3
    v = volvis.open(path)
    np.testing.assert_array_equal(v.array, arr)
    mem = volvis.World.open(path, mode="mip", size=(64, 64), tf=(0, 4000))
    ooc = volvis.World.open(path, mode="mip", size=(64, 64), tf=(0, 4000),
                            memory="out_of_core", memory_limit="64M", lod=True)
    assert ooc.opened["out_of_core"] and not mem.opened["out_of_core"]
    assert volvis.render(ooc, alpha=False).max() > 0


# ---- an OME-Zarr store ---------------------------------------------------------------------
@pytest.fixture(scope="module")
def store(tmp_path_factory):
    out = tmp_path_factory.mktemp("zarr") / "ct.ome.zarr"
    subprocess.run([cli(), "convert", str(CT), str(out), "-q"], check=True,
                   capture_output=True)
    return out


def test_store_in_memory_equals_cli(tmp_path, store):
    w, img = opened_render(store, (80, 80))
    assert w.opened["input"] == "volume"
    assert not w.opened["out_of_core"]
    assert w.objects[0].volume.array.shape == volvis.open(CT).array.shape
    np.testing.assert_array_equal(img, cli_render(tmp_path, store, "--size", "80x80"))


def test_store_out_of_core(store):
    # one transfer function for both: guessed, out of core it comes from the
    # coarsest level's range (only that level is read on opening), in
    # memory from every voxel
    mem = volvis.World.open(store, mode="mip", size=(80, 80), tf=(-1000, 1500))
    ooc = volvis.World.open(store, mode="mip", size=(80, 80), tf=(-1000, 1500),
                            memory="out_of_core", memory_limit="64M", lod=True)
    assert ooc.opened["out_of_core"] and not mem.opened["out_of_core"]
    assert volvis.memory_limit() == 64 << 20
    assert ooc._c.objects[0].source != volvis._ffi.NULL
    assert mem._c.objects[0].source == volvis._ffi.NULL
    # level 0 out of core is the in-memory render, MIP bit for bit
    a = volvis.render(mem, alpha=False)
    b = volvis.render(ooc, alpha=False, level=0)
    np.testing.assert_array_equal(a, b)
    # a coarser level is drawn from the pyramid's own level, not level 0
    c = volvis.render(ooc, alpha=False, level=2)
    assert c.any() and not np.array_equal(a, c)
    # the World keeps its file open; freeing it lets the cache go
    del mem, ooc
    gc.collect()
    volvis.memory_limit(1 << 30)


def test_out_of_core_if_able(store):
    w = volvis.World.open(NIFTI, memory="out_of_core_if_able")
    assert not w.opened["out_of_core"]
    w = volvis.World.open(store, memory="out_of_core_if_able")
    assert w.opened["out_of_core"]


# ---- a file of two channels ----------------------------------------------------------------
@pytest.fixture(scope="module")
def two_channels(tmp_path_factory):
    """A NRRD of two uint8 channels (an axis of kind vector), a ball in each."""
    z, y, x = np.mgrid[:20, :18, :16]
    a = ((x - 8) ** 2 + (y - 9) ** 2 + (z - 10) ** 2 < 30) * 200
    b = ((x - 4) ** 2 + (y - 5) ** 2 + (z - 6) ** 2 < 16) * 150
    d = np.stack([a, b], -1).astype(np.uint8)
    path = tmp_path_factory.mktemp("nrrd") / "two.nrrd"
    path.write_bytes(b"NRRD0004\ntype: uint8\ndimension: 4\nsizes: 2 16 18 20\n"
                     b"kinds: vector domain domain domain\nencoding: raw\n"
                     b"spacings: nan 1 1 1\n\n" + d.tobytes())
    return path


def test_channels_equal_cli(tmp_path, two_channels):
    w = volvis.World.open(two_channels)
    assert w.opened["n_channels"] == 2
    assert w._c.objects[0].n_channels == 2  # every channel, as volvis render FILE draws them
    np.testing.assert_array_equal(
        opened_render(two_channels, (64, 64))[1],
        cli_render(tmp_path, two_channels, "--size", "64x64"))
    w = volvis.World.open(two_channels, channel=1)
    assert w._c.objects[0].n_channels == 0  # --channel C: that channel alone
    w, img = opened_render(two_channels, (64, 64), channels=[0, 1], blend="maximum")
    assert w._c.objects[0].n_channels == 2
    np.testing.assert_array_equal(img, cli_render(tmp_path, two_channels, "--size", "64x64",
                                                  "--channels", "0,1", "--blend", "maximum"))
    w = volvis.World.open(two_channels, colors=[(1, 0, 0), (0, 1, 0)])
    assert w._c.objects[0].n_channels == 2  # colours alone: every channel of the file
    with pytest.raises(volvis.InvalidError) as e:
        volvis.World.open(two_channels, colors=[(1, 0, 0)] * 3)
    assert "two.nrrd" in str(e.value) and "2 channels" in str(e.value)


# ---- a scene -------------------------------------------------------------------------------
def test_scene_equals_cli(tmp_path):
    w, img = opened_render(SCENE, (120, 96))
    assert w.opened["input"] == "scene"
    assert (w.opened["n_channels"], w.opened["n_times"]) == (1, 1)
    np.testing.assert_array_equal(img, cli_render(tmp_path, SCENE, "--size", "120x96"))
    # a scene's transfer function stretched onto --tf, as the CLI does
    w, img = opened_render(SCENE, (120, 96), tf=(0, 2000))
    np.testing.assert_array_equal(
        img, cli_render(tmp_path, SCENE, "--size", "120x96", "--tf", "0:2000", name="tf.png"))


def test_scene_refuses_channels():
    with pytest.raises(volvis.InvalidError) as e:
        volvis.World.open(SCENE, channels=[0, 1])
    assert str(SCENE) in str(e.value) and "not a scene" in str(e.value)


# ---- errors --------------------------------------------------------------------------------
def test_errors_name_the_input(tmp_path):
    missing = tmp_path / "missing.nii"
    with pytest.raises(volvis.FileError) as e:
        volvis.World.open(missing)
    assert str(missing) in str(e.value)
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"not a volume at all\n" * 10)
    with pytest.raises(volvis.FormatError) as e:
        volvis.World.open(junk)
    assert "junk.bin" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(volvis.UnsupportedError) as e:
        volvis.World.open(NIFTI, memory="out_of_core")
    assert NIFTI.name in str(e.value)
    with pytest.raises(volvis.InvalidError) as e:
        volvis.World.open(NIFTI, channel=2)
    assert NIFTI.name in str(e.value)
    with pytest.raises(volvis.InvalidError):
        volvis.World.open(NIFTI, channels=[0, 1, 2])
    with pytest.raises(volvis.UnsupportedError) as e:
        volvis.World.open(NIFTI, lod=True)  # out of core by levels: a file read whole only
    assert NIFTI.name in str(e.value)
    for bad in (dict(memory="lots"), dict(blend="sum"), dict(channels="some"),
                dict(tf=(5, 1)), dict(size=(0, 10)), dict(step=0), dict(mode="fancy")):
        with pytest.raises(volvis.InvalidError):
            volvis.World.open(NIFTI, **bad)
    assert volvis.World().opened is None
    assert volvis.World.open(NIFTI).clone().opened is None


def test_memory_limit_kept_unless_given():
    before = volvis.memory_limit()
    try:
        volvis.memory_limit("256M")
        volvis.World.open(NIFTI)
        assert volvis.memory_limit() == 256 << 20
        volvis.World.open(NIFTI, memory_limit=300 << 20)
        assert volvis.memory_limit() == 300 << 20
    finally:
        volvis.memory_limit(before)
