"""The Python binding (src/bindings/python): keygraph.build through the
builder library (byte for byte what `keygraph build` writes), Index and
Detector on real frames, arrays of every layout, and bad input, which
raises an exception with a message and never crashes.

Environment (tests/python/CMakeLists.txt): KG_SCENES (the bindings' scenes:
scenes.kgi, box_in_scene.pgm, graf3.pgm, made by tests/capi/make_scenes.sh),
KG_OPENCV_DATA_DIR (opencv-doc's images), KG_FIND_CPP (the C++ reference).
"""
import os
import subprocess

import numpy as np
import pytest

import keygraph

SCENES = os.environ["KG_SCENES"]
DATA = os.environ["KG_OPENCV_DATA_DIR"]
INDEX = os.path.join(SCENES, "scenes.kgi")
GRAF_ROI = (200, 150, 300, 300)  # tests/support/opencv_scenes.h


def read_pgm(name):
    from find_scenes import read_pgm as read
    return read(os.path.join(SCENES, name))


@pytest.fixture(scope="module")
def index():
    return keygraph.Index(INDEX)


@pytest.fixture(scope="module")
def box_scene():
    return read_pgm("box_in_scene.pgm")


@pytest.fixture(scope="module")
def graf_scene():
    return read_pgm("graf3.pgm")


def reference(frame_name):
    """The C++ API's corners for a frame of the scenes (kg_find_cpp)."""
    out = subprocess.run([os.environ["KG_FIND_CPP"], INDEX, os.path.join(SCENES, frame_name)],
                         capture_output=True, text=True, check=True).stdout.split()
    return out[1], np.array([float(v) for v in out[2:10]]).reshape(4, 2)


def test_version_and_index(index):
    assert keygraph.__version__.count(".") == 2
    assert index.models == ["box", "graf"]
    assert index.format_version[0] >= 6
    assert "box" in repr(index)


def test_finds_box_and_graf_as_the_cpp_api(index, box_scene, graf_scene):
    detector = keygraph.Detector(index, max_width=800, max_height=640)
    for frame, name in ((box_scene, "box_in_scene.pgm"), (graf_scene, "graf3.pgm")):
        model, corners = reference(name)
        found = detector.detect(frame)
        assert [d.model for d in found] == [model]
        d = found[0]
        assert d.model_id == index.models.index(model)
        assert d.corners.shape == (4, 2) and d.corners.dtype == np.float64
        assert d.homography.shape == (3, 3)
        assert np.abs(d.corners - corners).max() < 0.01
        assert d.inliers >= 12 and 0.0 <= d.confidence <= 1.0
    stats = detector.stats
    assert stats["keypoints"] > 0 and stats["stopped_early"] is None


def test_every_array_layout_gives_the_same_corners(index, box_scene):
    detector = keygraph.Detector(index)
    expected = detector.detect(box_scene)[0].corners
    h, w = box_scene.shape
    wide = np.zeros((h, w + 13), dtype=np.uint8)
    wide[:, 3:3 + w] = box_scene
    layouts = {
        "rows padded (in place)": wide[:, 3:3 + w],
        "every other column of a doubled frame (copied)": np.repeat(box_scene, 2, axis=1)[:, ::2],
        "Fortran order (copied)": np.asfortranarray(box_scene),
        "flipped twice (negative strides, copied)": box_scene[::-1][::-1],
    }
    for name, frame in layouts.items():
        found = detector.detect(frame)
        assert len(found) == 1, name
        assert np.array_equal(found[0].corners, expected), name


def test_options_and_model_selection(index, box_scene):
    detector = keygraph.Detector(index, ransac_seed=7, **{"descriptor.max_search_leaves": 8})
    assert [d.model for d in detector.detect(box_scene)] == ["box"]
    detector.set_models(["graf"])
    detector.set_option("min_confidence", 0.0)  # an option keeps the selection
    assert detector.detect(box_scene) == []
    detector.set_models()
    assert len(detector.detect(box_scene)) == 1
    detector.set_option("min_confidence", 1)
    assert detector.detect(box_scene) == []


def test_bad_arrays_raise(index, box_scene):
    detector = keygraph.Detector(index)
    with pytest.raises(TypeError, match="uint8"):
        detector.detect(box_scene.astype(np.float32))
    with pytest.raises(TypeError, match="uint8"):
        detector.detect(box_scene.astype(np.uint16))
    with pytest.raises(ValueError, match="2-D.*convert colour to grey"):
        detector.detect(np.dstack([box_scene] * 3))
    with pytest.raises(ValueError, match="2-D"):
        detector.detect(box_scene.ravel())
    with pytest.raises(ValueError, match="empty"):
        detector.detect(np.zeros((0, 10), dtype=np.uint8))
    with pytest.raises(TypeError, match="numpy array"):
        detector.detect(box_scene.tolist())
    with pytest.raises(keygraph.Error, match="larger than the detector's limits") as e:
        detector.detect(np.zeros((481, 640), dtype=np.uint8))
    assert e.value.status == 1 and e.value.status_name == "InvalidArgument"


def test_bad_detectors_and_options_raise(index):
    with pytest.raises(TypeError, match="keygraph.Index"):
        keygraph.Detector(None)
    with pytest.raises(keygraph.Error, match="limits"):
        keygraph.Detector(index, max_width=0)
    with pytest.raises(keygraph.Error, match="threads"):
        keygraph.Detector(index, threads=65)
    detector = keygraph.Detector(index)
    with pytest.raises(keygraph.Error, match="no.such"):
        detector.set_option("no.such", 1)
    with pytest.raises(keygraph.Error, match="fixed by the index"):
        keygraph.Detector(index, graph_structure=4)
    with pytest.raises(keygraph.Error, match="min_confidence"):
        detector.set_option("min_confidence", 2)
    with pytest.raises(keygraph.Error, match="not in the index"):
        detector.set_models([5])
    with pytest.raises(ValueError, match="no model 'sign'"):
        detector.set_models(["sign"])


def test_bad_indexes_raise(tmp_path):
    with pytest.raises(keygraph.Error, match="nowhere.kgi") as e:
        keygraph.Index(tmp_path / "nowhere.kgi")
    assert e.value.status_name == "NotFound"
    with pytest.raises(keygraph.Error):
        keygraph.Index(tmp_path)  # a directory
    data = open(INDEX, "rb").read()
    assert keygraph.Index.from_bytes(data).models == ["box", "graf"]
    for corrupt in (data[: len(data) // 2], data[:100], b"",
                    data[:5000] + bytes([data[5000] ^ 0x40]) + data[5001:]):
        with pytest.raises(keygraph.Error) as e:
            keygraph.Index.from_bytes(corrupt)
        assert e.value.status_name == "CorruptData" and str(e.value)
    (tmp_path / "junk.kgi").write_bytes(b"not an index at all" * 10)
    with pytest.raises(keygraph.Error, match="junk.kgi"):
        keygraph.Index(tmp_path / "junk.kgi")


def test_build_writes_what_the_cli_writes(tmp_path):
    """keygraph.build through the builder library: the scenes' index, as
    tests/capi/make_scenes.sh built it with `keygraph build`, byte for byte."""
    out = tmp_path / "scenes.kgi"
    assert keygraph.build([os.path.join(DATA, "box.png"), (os.path.join(DATA, "graf1.png"), GRAF_ROI)],
                          out, names=["box", "graf"], look_alikes=False) == os.fspath(out)
    assert out.read_bytes() == open(INDEX, "rb").read()


def test_build_from_arrays_and_options(tmp_path, box_scene):
    box = read_pgm("box_in_scene.pgm")[100:300, 50:300]  # a region of a frame, strided rows
    out = tmp_path / "arrays.kgi"
    keygraph.build([box, (np.ascontiguousarray(box), (0, 0, 200, 150))], out,
                   names=["crop", "smaller"], preset="frontal", look_alikes=False,
                   ransac_seed=11, **{"keypoints.max_model_keypoints": 300})
    index = keygraph.Index(out)
    assert index.models == ["crop", "smaller"]
    assert len(keygraph.Detector(index).detect(box_scene)) >= 1


def test_build_bad_input_raises_and_leaves_nothing(tmp_path):
    out = tmp_path / "out.kgi"
    box = os.path.join(DATA, "box.png")
    with pytest.raises(keygraph.Error, match="nowhere.png"):
        keygraph.build([str(tmp_path / "nowhere.png")], out)
    with pytest.raises(keygraph.Error, match="no.such"):
        keygraph.build([box], out, **{"no.such": 1})
    with pytest.raises(keygraph.Error, match="preset"):
        keygraph.build([box], out, preset="sideways")
    with pytest.raises(keygraph.Error):
        keygraph.build([box, box], out, names=["same", "same"])
    with pytest.raises(keygraph.Error):
        keygraph.build([(box, (300, 200, 100, 100))], out)  # the region leaves the image
    with pytest.raises(ValueError, match="names"):
        keygraph.build([box], out, names=["a", "b"])
    with pytest.raises(TypeError, match="list"):
        keygraph.build(box, out)
    with pytest.raises(TypeError, match="uint8"):
        keygraph.build([np.zeros((50, 50), dtype=np.float64)], out)
    with pytest.raises(ValueError, match="2-D"):
        keygraph.build([np.zeros((50, 50, 3), dtype=np.uint8)], out)
    assert list(tmp_path.iterdir()) == []


def test_tracker_follows_the_box(index, box_scene):
    detector = keygraph.Detector(index)
    tracker = keygraph.Tracker(detector)
    assert tracker.can_track
    h, w = box_scene.shape
    ids, tracked = set(), 0
    for k in range(12):
        window = box_scene[2 * k:2 * k + h - 24, 4 * k:4 * k + w - 48]  # a view, no copy
        found = tracker.process(window)
        assert [d.model for d in found] == ["box"], k
        ids.add(found[0].track_id)
        tracked += found[0].tracked
    assert len(ids) == 1 and min(ids) >= 0
    assert tracked >= 10
    assert tracker.stats["frames"] == 12
    tracker.reset()
    assert tracker.stats["frames"] == 0
    with pytest.raises(keygraph.Error, match="detect_interval"):
        keygraph.Tracker(detector, detect_interval=0)
    with pytest.raises(TypeError, match="unknown tracker option"):
        keygraph.Tracker(detector, interval=3)
    with pytest.raises(keygraph.Error, match="larger than"):
        tracker.process(np.zeros((481, 640), dtype=np.uint8))


def test_build_refuses_a_decompression_bomb_in_process(tmp_path):
    """The pixel limit holds inside a Python process (issue 37, item 6): a
    PNG of 5000x5000 (25 megapixels, 25 KB) is refused from its header,
    before decoding, with no environment set."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = zlib.compress(b"\0" * (5001 * 5000), 9)
    bomb = tmp_path / "bomb.png"
    bomb.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 5000, 5000, 8, 0, 0, 0, 0))
                     + chunk(b"IDAT", rows) + chunk(b"IEND", b""))
    assert bomb.stat().st_size < 100_000
    with pytest.raises(keygraph.Error, match="5000x5000 pixels is over 16777216 pixels.*not decoded") as e:
        keygraph.build([bomb], tmp_path / "out.kgi")
    assert e.value.status_name == "ResourceExhausted"
    assert not (tmp_path / "out.kgi").exists()
