"""The ctypes declarations of libkodawari.so (engine/include/kodawari/kodawari.h) that the
package uses, and where the library is found. Internal: use kodawari.Simulation."""
import ctypes
import os

from . import _config

# kodawari.h's structs, field for field (C layout: ctypes follows the platform's rules).


class BackendOptions(ctypes.Structure):
    _fields_ = [
        ("backend", ctypes.c_int32),
        ("device", ctypes.c_char_p),
        ("validation", ctypes.c_uint32),
        ("threads", ctypes.c_uint32),
        ("vulkan_device", ctypes.c_void_p),
        ("isa", ctypes.c_char_p),
        ("workgroup_size", ctypes.c_uint32),
    ]


class SimulationInfo(ctypes.Structure):
    _fields_ = [
        ("bird_count", ctypes.c_uint32),
        ("character_count", ctypes.c_uint32),
        ("chain_count", ctypes.c_uint32),
        ("joint_count", ctypes.c_uint32),
        ("frame_count", ctypes.c_uint32),
        ("next_frame", ctypes.c_uint32),
        ("fps", ctypes.c_float),
        ("backend", ctypes.c_int32),
        ("validation_messages", ctypes.c_uint32),
        ("name", ctypes.c_char * 256),
        ("device", ctypes.c_char * 256),
        ("fallback_reason", ctypes.c_char * 1024),
    ]


class BirdOutput(ctypes.Structure):
    _fields_ = [
        ("local_transforms", ctypes.c_void_p),
        ("local_transforms_capacity", ctypes.c_size_t),
        ("world_transforms", ctypes.c_void_p),
        ("world_transforms_capacity", ctypes.c_size_t),
    ]


class LodBudget(ctypes.Structure):
    _fields_ = [("active", ctypes.c_uint32), ("measured", ctypes.c_uint32), ("budget_ms", ctypes.c_float),
                ("scale", ctypes.c_float), ("full_distance", ctypes.c_float), ("modelled_ms", ctypes.c_float)]


class ChainOutput(ctypes.Structure):
    _fields_ = [
        ("positions", ctypes.c_void_p),
        ("positions_capacity", ctypes.c_size_t),
        ("orientations", ctypes.c_void_p),
        ("orientations_capacity", ctypes.c_size_t),
        ("rest_positions", ctypes.c_void_p),
        ("rest_positions_capacity", ctypes.c_size_t),
        ("view_directions", ctypes.c_void_p),
        ("view_directions_capacity", ctypes.c_size_t),
        ("weights", ctypes.c_void_p),
        ("weights_capacity", ctypes.c_size_t),
    ]


# kodawari_backend.
BACKENDS = {"auto": 0, "cpu-reference": 1, "cpu": 2, "vulkan": 3}
BACKEND_NAMES = {value: name for name, value in BACKENDS.items()}
# kodawari.h's constants.
BIRD_PARTS = 7
TRANSFORM_FLOATS = 7
WEIGHTS_PER_CHAIN = 8


def library_candidates():
    """Where the library may be, in order: next to this file (an installed package, and the
    build tree's python/ folder, where the build copies it)."""
    here = os.path.dirname(os.path.abspath(__file__))
    return [os.path.join(here, _config.LIBRARY)]


def _preload(folder):
    """Loads the libraries _config.PRELOAD names from `folder`: once loaded, the dynamic
    loader takes them for the library's dependencies of the same SONAME. One of them may
    need another (tinygltf needs stb): those that fail are tried again after the rest."""
    left = list(getattr(_config, "PRELOAD", ()))
    while left:
        failed, errors = [], []
        for name in left:
            try:
                ctypes.CDLL(os.path.join(folder, name))
            except OSError as error:
                failed.append(name)
                errors.append(str(error))
        if len(failed) == len(left):
            raise ImportError("kodawari: cannot load " + "; ".join(errors))
        left = failed


def _load():
    tried = []
    for path in library_candidates():
        if os.path.exists(path):
            _preload(os.path.dirname(path))
            return ctypes.CDLL(path), path
        tried.append(path)
    raise ImportError(f"kodawari: {_config.LIBRARY} not found (looked for {', '.join(tried)}); "
                      "build the project (cmake --build) or install its python component")


class Wind(ctypes.Structure):
    _fields_ = [("velocity", ctypes.c_float * 3), ("gust", ctypes.c_float), ("gust_period", ctypes.c_float),
                ("gust_size", ctypes.c_float), ("seed", ctypes.c_uint32)]


class FlockAgent(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_uint32), ("position", ctypes.c_float * 3), ("velocity", ctypes.c_float * 3),
                ("radius", ctypes.c_float), ("weight", ctypes.c_float), ("margin", ctypes.c_float),
                ("end", ctypes.c_float * 3), ("normal", ctypes.c_float * 3)]


lib, library_path = _load()

_P = ctypes.POINTER
_sim = ctypes.c_void_p
_status = ctypes.c_int32


def _declare(name, restype, *argtypes):
    function = getattr(lib, name)
    function.restype = restype
    function.argtypes = list(argtypes)


_declare("kodawari_version", ctypes.c_char_p)
_declare("kodawari_status_name", ctypes.c_char_p, _status)
_declare("kodawari_last_error", ctypes.c_char_p)
_declare("kodawari_simulation_open", _status, ctypes.c_char_p, _P(BackendOptions), ctypes.c_uint32, _P(_sim))
_declare("kodawari_simulation_destroy", None, _sim)
_declare("kodawari_simulation_last_error", ctypes.c_char_p, _sim)
_declare("kodawari_simulation_step", _status, _sim, ctypes.c_uint32)
_declare("kodawari_simulation_set_wind", _status, _sim, _P(Wind))
_declare("kodawari_simulation_set_lod_budget", _status, _sim, ctypes.c_float, ctypes.c_int)
_declare("kodawari_simulation_set_flock_agents", _status, _sim, _P(FlockAgent), ctypes.c_uint32)
_declare("kodawari_simulation_get_info", _status, _sim, _P(SimulationInfo))
_declare("kodawari_simulation_bird_poses", _status, _sim, _P(BirdOutput))
_declare("kodawari_simulation_bird_tail_spreads", _status, _sim, ctypes.c_void_p, ctypes.c_size_t)
_declare("kodawari_simulation_read_chains", _status, _sim, _P(ChainOutput))
_declare("kodawari_simulation_chain_levels", _status, _sim, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)
_declare("kodawari_simulation_lod_budget", _status, _sim, _P(LodBudget))
_declare("kodawari_simulation_chain_joints", _status, _sim, ctypes.c_uint32, _P(ctypes.c_uint32),
         _P(ctypes.c_uint32))
_declare("kodawari_simulation_bake", _status, _sim, ctypes.c_char_p, ctypes.c_uint32, ctypes.c_char_p,
         ctypes.c_size_t)
_declare("kodawari_rig_scene", _status, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_float,
         ctypes.c_char_p, ctypes.c_size_t)
