"""The C API (include/keygraph/keygraph.h) through ctypes, and
keygraph.build()'s builder entry point (kgpy_build), both in
libkeygraph_python.so beside this file. Declarations only: keygraph's
Python API is in __init__.py."""
import ctypes
import os

_LIBRARY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "libkeygraph_python.so")
lib = ctypes.CDLL(_LIBRARY)

c_int, c_char_p, c_void_p, c_size_t = ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p, ctypes.c_size_t
c_double, c_ssize_t = ctypes.c_double, ctypes.c_ssize_t  # ptrdiff_t is ssize_t on Linux


class Limits(ctypes.Structure):
    """kg_limits"""
    _fields_ = [(name, c_int) for name in (
        "max_width", "max_height", "max_keypoints", "max_scene_keypoints", "max_arc_matches",
        "max_arc_pool", "max_correspondences", "max_detections", "threads")]


class Image(ctypes.Structure):
    """kg_image"""
    _fields_ = [("data", c_void_p), ("width", c_int), ("height", c_int), ("stride", c_ssize_t)]


class RawDetection(ctypes.Structure):
    """kg_detection"""
    _fields_ = [
        ("model_id", c_int), ("model_name", c_char_p), ("homography", c_double * 9),
        ("corners", (c_double * 2) * 4), ("inliers", c_int), ("inlier_keygraphs", c_int),
        ("score", c_double), ("chance", c_double), ("rms_error", c_double),
        ("verification_z", c_double), ("appearance", c_double), ("confidence", c_double),
        ("ransac_iterations", c_int), ("track_id", c_int), ("tracked", c_int)]


class TrackerOptions(ctypes.Structure):
    """kg_tracker_options"""
    _fields_ = [("detect_interval", c_int), ("min_correlation", c_double), ("max_tracks", c_int),
                ("smoothing", c_double)]


class TrackerStats(ctypes.Structure):
    """kg_tracking_stats"""
    _fields_ = [("tracks", c_int), ("confirmed", c_int), ("lost", c_int), ("detected", c_int),
                ("ms_track", c_double), ("ms_detect", c_double), ("frames", ctypes.c_longlong),
                ("detected_frames", ctypes.c_longlong)]


class Stats(ctypes.Structure):
    """kg_stats"""
    _fields_ = [
        ("keypoints", c_int), ("sampled_keypoints", c_int), ("keygraphs", c_int),
        ("arcs_described", c_int), ("arc_matches", ctypes.c_longlong), ("correspondences", c_int),
        ("ransac_iterations", c_int), ("truncated_keypoints", c_int),
        ("truncated_arc_matches", c_int), ("truncated_correspondences", c_int),
        ("truncated_detections", c_int), ("ms_keypoints", c_double), ("ms_graph", c_double),
        ("ms_describe", c_double), ("ms_select", c_double), ("ms_pose", c_double),
        ("stopped_early", c_char_p)]


MAX_DETECTIONS = 64  # KG_MAX_DETECTIONS


def _declare(name, restype, *argtypes):
    function = getattr(lib, name)
    function.restype = restype
    function.argtypes = list(argtypes)
    return function


_P = ctypes.POINTER
status_name = _declare("kg_status_name", c_char_p, c_int)
last_error = _declare("kg_last_error", c_char_p)
version = _declare("kg_version", c_char_p)
index_read = _declare("kg_index_read", c_int, c_char_p, _P(c_void_p))
index_from_memory = _declare("kg_index_from_memory", c_int, c_void_p, c_size_t, _P(c_void_p))
index_destroy = _declare("kg_index_destroy", None, c_void_p)
index_version = _declare("kg_index_version", c_int, c_void_p, _P(c_int), _P(c_int))
index_model_count = _declare("kg_index_model_count", c_int, c_void_p)
index_model_name = _declare("kg_index_model_name", c_char_p, c_void_p, c_int)
limits_default = _declare("kg_limits_default", None, _P(Limits))
detector_create = _declare("kg_detector_create", c_int, c_void_p, _P(Limits), _P(c_void_p))
detector_destroy = _declare("kg_detector_destroy", None, c_void_p)
detector_set_option = _declare("kg_detector_set_option", c_int, c_void_p, c_char_p, c_char_p)
detector_set_models = _declare("kg_detector_set_models", c_int, c_void_p, _P(ctypes.c_int32), c_size_t)
detect = _declare("kg_detect", c_int, c_void_p, _P(Image), _P(RawDetection), c_size_t, _P(c_size_t))
detector_stats = _declare("kg_detector_stats", c_int, c_void_p, _P(Stats))
tracker_options_default = _declare("kg_tracker_options_default", None, _P(TrackerOptions))
tracker_create = _declare("kg_tracker_create", c_int, c_void_p, _P(TrackerOptions), _P(c_void_p))
tracker_destroy = _declare("kg_tracker_destroy", None, c_void_p)
tracker_can_track = _declare("kg_tracker_can_track", c_int, c_void_p)
tracker_process = _declare("kg_tracker_process", c_int, c_void_p, _P(Image), _P(RawDetection), c_size_t,
                           _P(c_size_t))
tracker_reset = _declare("kg_tracker_reset", None, c_void_p)
tracker_stats = _declare("kg_tracker_stats", c_int, c_void_p, _P(TrackerStats))
build = _declare("kgpy_build", c_int, c_char_p, c_int, _P(c_char_p), _P(c_void_p), _P(c_int),
                 _P(c_int), _P(c_ssize_t), _P(c_int), _P(c_char_p), c_int, _P(c_char_p),
                 _P(c_char_p), c_char_p, c_int, c_int, ctypes.c_char_p, c_size_t)
