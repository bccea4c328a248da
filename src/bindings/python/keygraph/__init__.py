"""keygraph: planar object detection with keygraphs (Hashimoto & Cesar).

    import keygraph
    keygraph.build(["box.png", ("graf1.png", (200, 150, 300, 300))], "scenes.kgi",
                   names=["box", "graf"])
    index = keygraph.Index("scenes.kgi")
    detector = keygraph.Detector(index, max_width=1280, max_height=720)
    for d in detector.detect(gray):          # a 2-D uint8 numpy array
        print(d.model, d.corners, d.confidence)

The detector is keygraph's C++ core behind its C API (keygraph/keygraph.h),
reached through ctypes; keygraph.build() runs the desktop builder, as
`keygraph build` does. Conventions: pixel (x, y) is column x, row y, the
top-left pixel's centre is (0, 0); a homography maps model pixels to frame
pixels. Errors from the library raise keygraph.Error (with .status, the C
API's code); a bad array raises TypeError or ValueError.
"""
import os
import threading

import numpy as np

from . import _native

__all__ = ["Error", "Index", "Detector", "Detection", "Tracker", "build", "__version__"]

__version__ = _native.version().decode()


class Error(Exception):
    """A keygraph call failed: .status is the C API's code (1 InvalidArgument,
    2 NotFound, 3 IoError, 4 CorruptData, 5 UnsupportedVersion, 6
    ResourceExhausted), .status_name its name."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status
        self.status_name = _native.status_name(status).decode()


def _check(status):
    if status != 0:
        raise Error(status, _native.last_error().decode(errors="replace"))


def _gray_plane(image, what="image"):
    """The array as the C API takes it: (array, row stride). Rows are used in
    place when their pixels are contiguous; any other layout is copied."""
    if not isinstance(image, np.ndarray):
        raise TypeError(f"{what} must be a numpy array, got {type(image).__name__}")
    if image.dtype != np.uint8:
        raise TypeError(f"{what} must be 8-bit grey (dtype uint8), got {image.dtype}")
    if image.ndim != 2:
        raise ValueError(f"{what} must be 2-D (height, width) grey, got shape {image.shape}"
                         + (": convert colour to grey first" if image.ndim == 3 else ""))
    height, width = image.shape
    if height == 0 or width == 0:
        raise ValueError(f"{what} is empty (shape {image.shape})")
    if image.strides[1] != 1 or image.strides[0] < width:
        image = np.ascontiguousarray(image)
    return image, image.strides[0]


def _option_name(key):
    """A keyword as a parameter name: "ransac.seed" stays; ransac_seed,
    views_max_tilt: the group before the first underscore."""
    if "." in key or key in ("min_confidence", "time_budget_ms"):
        return key
    group, _, field = key.partition("_")
    return f"{group}.{field}" if field else key


def _option_value(value):
    if isinstance(value, bool):
        return "1" if value else "0"
    return str(value)


class Index:
    """A model index (.kgi), read into memory and validated: a corrupt or
    hostile file raises Error, never crashes. Read-only: one index may serve
    detectors on several threads."""

    def __init__(self, path):
        handle = _native.c_void_p()
        _check(_native.index_read(os.fsencode(path), handle))
        self._handle = handle
        self._memory = None
        self._load_names()

    @classmethod
    def from_bytes(cls, data):
        """An index from bytes in memory (copied once into 64-byte aligned
        memory the index owns)."""
        view = memoryview(data).cast("B")
        storage = np.empty(len(view) + 64, dtype=np.uint8)
        start = (-storage.ctypes.data) % 64
        storage[start:start + len(view)] = np.frombuffer(view, dtype=np.uint8)
        self = cls.__new__(cls)
        handle = _native.c_void_p()
        _check(_native.index_from_memory(storage.ctypes.data + start, len(view), handle))
        self._handle = handle
        self._memory = storage
        self._load_names()
        return self

    def _load_names(self):
        count = _native.index_model_count(self._handle)
        self.models = [_native.index_model_name(self._handle, i).decode(errors="replace")
                       for i in range(count)]
        major, minor = _native.c_int(), _native.c_int()
        _check(_native.index_version(self._handle, major, minor))
        self.format_version = (major.value, minor.value)

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.index_destroy(handle)
            self._handle = None

    def __repr__(self):
        return f"keygraph.Index({len(self.models)} models: {', '.join(self.models)})"


class Detection:
    """One object found in a frame."""
    __slots__ = ("model", "model_id", "corners", "homography", "inliers", "confidence", "score",
                 "appearance", "rms_error", "track_id", "tracked")

    def __init__(self, raw):
        self.model = raw.model_name.decode(errors="replace")  # the model's name
        self.model_id = raw.model_id
        # The model's outline in the frame, 4x2 (x, y), clockwise from its top-left.
        self.corners = np.array([[raw.corners[c][0], raw.corners[c][1]] for c in range(4)])
        self.homography = np.array(raw.homography[:], dtype=np.float64).reshape(3, 3)
        self.inliers = raw.inliers  # distinct keypoint correspondences within the threshold
        self.confidence = raw.confidence  # estimated probability, in [0, 1], that it is right
        self.score = raw.score  # fraction of the model's keypoints confirmed
        self.appearance = raw.appearance  # appearance correlation in [0, 1]; -1: not measured
        self.rms_error = raw.rms_error  # reprojection error of the inliers, pixels
        self.track_id = raw.track_id  # Tracker only: the object's id while followed; -1 otherwise
        self.tracked = bool(raw.tracked)  # Tracker only: confirmed around its prediction

    def __repr__(self):
        corners = ", ".join(f"({x:.1f}, {y:.1f})" for x, y in self.corners)
        return (f"keygraph.Detection({self.model!r}, corners=[{corners}], inliers={self.inliers}, "
                f"confidence={self.confidence:.3f})")


_LIMITS = tuple(name for name, _ in _native.Limits._fields_)


class Detector:
    """Detects an index's models in 8-bit grey frames.

    Keywords: the limits (max_width and max_height, default 640x480: a larger
    frame is an error; max_keypoints, max_detections, threads, ...), which
    size the workspace allocated here once; and runtime options by name, as
    `keygraph detect --set` spells them: ransac_seed=7 or
    **{"ransac.seed": 7}, min_confidence=0.5, time_budget_ms=30,
    descriptor_max_search_leaves=16.

    Calls on one detector are serialised by a lock; use one detector per
    thread to detect in parallel (the library runs without the GIL)."""

    def __init__(self, index, **options):
        if not isinstance(index, Index):
            raise TypeError(f"Detector needs a keygraph.Index, got {type(index).__name__}")
        limits = _native.Limits()
        _native.limits_default(limits)
        for key in [k for k in options if k in _LIMITS]:
            setattr(limits, key, int(options.pop(key)))
        handle = _native.c_void_p()
        _check(_native.detector_create(index._handle, limits, handle))
        self._handle = handle
        self._index = index  # outlives the detector
        self._lock = threading.Lock()
        self._found = (_native.RawDetection * _native.MAX_DETECTIONS)()
        self.limits = {name: getattr(limits, name) for name in _LIMITS}
        for key, value in options.items():
            self.set_option(_option_name(key), value)

    def set_option(self, name, value):
        """Sets the runtime option `name` ("ransac.seed", "min_confidence", ...)."""
        with self._lock:
            _check(_native.detector_set_option(self._handle, str(name).encode(),
                                               _option_value(value).encode()))

    def set_models(self, models=None):
        """The models to look for, by id or name (None: every model)."""
        ids = []
        for m in models or []:
            if isinstance(m, str):
                if m not in self._index.models:
                    raise ValueError(f"no model {m!r} in the index ({', '.join(self._index.models)})")
                m = self._index.models.index(m)
            ids.append(int(m))
        array = (_native.ctypes.c_int32 * max(1, len(ids)))(*ids)
        with self._lock:
            _check(_native.detector_set_models(self._handle, array, len(ids)))

    def detect(self, image):
        """The detections in `image`, a 2-D uint8 numpy array (any strides;
        rows with contiguous pixels are read in place, without a copy)."""
        return self._run(_native.detect, self._handle, image)

    def _run(self, function, handle, image):
        """A frame through `function` (kg_detect, kg_tracker_process on `handle`)."""
        plane, stride = _gray_plane(image)
        height, width = plane.shape
        frame = _native.Image(plane.ctypes.data, width, height, stride)
        count = _native.c_size_t()
        with self._lock:
            _check(function(handle, frame, self._found, _native.MAX_DETECTIONS, count))
            return [Detection(self._found[i]) for i in range(count.value)]

    @property
    def stats(self):
        """The last frame's statistics (kg_stats) as a dict."""
        stats = _native.Stats()
        with self._lock:
            _check(_native.detector_stats(self._handle, stats))
        out = {name: getattr(stats, name) for name, _ in _native.Stats._fields_}
        if out["stopped_early"] is not None:
            out["stopped_early"] = out["stopped_early"].decode()
        return out

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.detector_destroy(handle)
            self._handle = None


class Tracker:
    """Follows what a Detector finds from frame to frame (live video): each
    object's corners are predicted and confirmed by aligning the model's
    stored appearance; full detection runs when nothing is followed, when an
    object is lost and every detect_interval frames; an object keeps its
    .track_id while followed (.tracked: confirmed without a detection).

    Options: detect_interval=10, min_correlation=0.75, max_tracks=16,
    smoothing=0.0 (keygraph/tracker.h). Frames in order; the detector's lock
    is held for each frame, so it serves no one else meanwhile."""

    def __init__(self, detector, **options):
        if not isinstance(detector, Detector):
            raise TypeError(f"Tracker needs a keygraph.Detector, got {type(detector).__name__}")
        settings = _native.TrackerOptions()
        _native.tracker_options_default(settings)
        for key, value in options.items():
            if key not in dict(_native.TrackerOptions._fields_):
                raise TypeError(f"unknown tracker option {key!r}")
            setattr(settings, key, value)
        handle = _native.c_void_p()
        with detector._lock:
            _check(_native.tracker_create(detector._handle, settings, handle))
        self._handle = handle
        self._detector = detector  # outlives the tracker
        self.can_track = bool(_native.tracker_can_track(handle))

    def process(self, image):
        """The objects in `image` (as Detector.detect takes it)."""
        return self._detector._run(_native.tracker_process, self._handle, image)

    def reset(self):
        """Forgets every track (a new scene, a camera switch)."""
        with self._detector._lock:
            _native.tracker_reset(self._handle)

    @property
    def stats(self):
        """The last frame's tracking statistics (kg_tracker_stats) as a dict."""
        stats = _native.TrackerStats()
        with self._detector._lock:
            _check(_native.tracker_stats(self._handle, stats))
        return {name: getattr(stats, name) for name, _ in _native.TrackerStats._fields_}

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.tracker_destroy(handle)
            self._handle = None


def build(images, output, names=None, **options):
    """Builds a model index (.kgi) at `output` from model images, through
    keygraph's builder library, as `keygraph build` does (the same images
    and parameters give the same file, byte for byte).

    images: each a file path (PNG, JPEG, ...), a 2-D uint8 numpy array, or
        (path or array, (x, y, w, h)) for a region of it.
    names: one per image; default the file's stem, "model<i>" for an array.
    options: preset="frontal" | "angled" | "defaults"; threads=0 (one per
        CPU); look_alikes=True (the quality report's look-alike check, as
        --no-look-alikes turns off); any parameter of keygraph/params.h by
        name, as --set spells it: **{"views.max_tilt": 30} or views_max_tilt=30.
    Returns `output`. Raises Error (bad images, names or parameters;
    the file is then left as it was) or TypeError/ValueError (bad arrays).
    """
    if isinstance(images, (str, bytes, os.PathLike, np.ndarray)):
        raise TypeError("images must be a list of model images")
    images = list(images)
    if not images:
        raise ValueError("build: no model images")
    if names is not None and len(names) != len(images):
        raise ValueError(f"build: {len(names)} names for {len(images)} images")
    preset = options.pop("preset", None)
    threads = int(options.pop("threads", 0))
    look_alikes = bool(options.pop("look_alikes", True))
    n = len(images)
    paths = (_native.c_char_p * n)()
    pixels = (_native.c_void_p * n)()
    widths, heights = (_native.c_int * n)(), (_native.c_int * n)()
    strides = (_native.c_ssize_t * n)()
    rois = (_native.c_int * (4 * n))()
    model_names = (_native.c_char_p * n)()
    keep = []  # arrays handed over, alive until the build returns
    for i, item in enumerate(images):
        roi = None
        if isinstance(item, tuple):
            if len(item) != 2 or len(item[1]) != 4:
                raise ValueError(f"build: image {i}: expected (image, (x, y, w, h)), got {item!r}")
            item, roi = item
            x, y, w, h = (int(v) for v in roi)
            if w <= 0 or h <= 0 or x < 0 or y < 0:
                raise ValueError(f"build: image {i}: bad region {roi!r}")
            rois[4 * i:4 * i + 4] = [x, y, w, h]
        if isinstance(item, np.ndarray):
            plane, stride = _gray_plane(item, f"image {i}")
            keep.append(plane)
            pixels[i] = plane.ctypes.data
            heights[i], widths[i] = plane.shape
            strides[i] = stride
            default_name = f"model{i}"
        else:
            path = os.fspath(item)
            paths[i] = os.fsencode(path)
            default_name = os.path.splitext(os.path.basename(path))[0]
        model_names[i] = (names[i] if names is not None else default_name).encode()
    keys = list(options)
    param_names = (_native.c_char_p * max(1, len(keys)))(*[_option_name(k).encode() for k in keys])
    param_values = (_native.c_char_p * max(1, len(keys)))(
        *[_option_value(options[k]).encode() for k in keys])
    error = _native.ctypes.create_string_buffer(1024)
    status = _native.build(os.fsencode(os.fspath(output)), n, paths, pixels, widths, heights, strides,
                           rois, model_names, len(keys), param_names, param_values,
                           preset.encode() if preset else None, threads, int(look_alikes), error,
                           len(error))
    if status != 0:
        raise Error(status, error.value.decode(errors="replace"))
    return os.fspath(output)
