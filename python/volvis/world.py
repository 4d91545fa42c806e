"""The World of the VolVis paper (section 3, "Abstract model") in Python:
views, lights, cut planes, materials, transfer functions, objects, and
scene files (docs/scene-format.md).

Units: world units for positions and distances (the volume files', usually
mm); angles in DEGREES, as in scene files and on the command line (the
library works in radians; the package converts). Colours are (r, g, b) in
[0, 1]; quaternions (w, x, y, z).

Proxies: ``world.view``, ``world.lights[i]``, ``obj.material``, ``obj.tf``
... read and write the library's structs in place (a change is seen by the
next render). A standalone ``View()``, ``Light()``, ``TransferFunction()``
owns its own struct; assigning it (``obj.tf = tf``) copies it.

Thread-safety: a World may be rendered by several threads at once; changing
it while a render reads it is the caller's to prevent (render a
``world.clone()`` instead).
"""
import math
import os
import weakref

import numpy as np

from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import Volume, _mat4, _vec3

__all__ = ["View", "Light", "CutPlane", "Material", "TransferFunction", "TransferFunction2D",
           "Object", "VolumeObject", "GridObject", "Sphere", "Box", "Plane", "Cylinder",
           "Polygon", "MeshObject", "World", "load_scene", "tf_presets"]


def _v3(c):
    return (c.x, c.y, c.z)


def _set_v3(c, value, what):
    v = _vec3(value, what)
    c.x, c.y, c.z = float(v[0]), float(v[1]), float(v[2])


def _color(value, what):
    v = _vec3(value, what)
    if np.any(v < 0) or np.any(v > 1):
        raise InvalidError("%s: colour components must be in [0, 1], got %s" % (what, tuple(v)))
    return v


def _vec_prop(field, doc, color=False):
    def get(self):
        return _v3(getattr(self._c, field))

    def set_(self, value):
        if color:
            _color(value, field)
        _set_v3(getattr(self._c, field), value, field)
    return property(get, set_, doc=doc)


def _num_prop(field, doc, lo=None, hi=None, integer=False):
    def get(self):
        return getattr(self._c, field)

    def set_(self, value):
        v = int(value) if integer else float(value)
        if not math.isfinite(v) or (lo is not None and v < lo) or (hi is not None and v > hi):
            raise InvalidError("%s: %r is outside [%s, %s]" % (field, value, lo, hi))
        setattr(self._c, field, v)
    return property(get, set_, doc=doc)


def _bool_prop(field, doc):
    def get(self):
        return bool(getattr(self._c, field))

    def set_(self, value):
        setattr(self._c, field, 1 if value else 0)
    return property(get, set_, doc=doc)


class _Struct:
    """A proxy of a C struct: owned (ffi.new) or inside a library object
    whose Python owner it keeps alive."""
    __slots__ = ("_c", "_owner")
    _ctype = None
    _fields = ()

    def _new(self, kw):
        self._c = ffi.new(self._ctype + " *")
        self._owner = None
        self._init()
        for k, v in kw.items():
            if k not in self._fields:
                raise InvalidError("%s: unknown argument %r (%s)" % (
                    type(self).__name__, k, ", ".join(self._fields)))
            if v is not None:
                setattr(self, k, v)

    def _init(self):
        pass

    @classmethod
    def _at(cls, cptr, owner):
        obj = cls.__new__(cls)
        obj._c = cptr
        obj._owner = owner
        return obj

    def copy(self):
        """An independent copy that owns its struct."""
        obj = type(self).__new__(type(self))
        obj._c = ffi.new(self._ctype + " *", self._c[0])
        obj._owner = None
        return obj

    def _value(self):
        return self._c[0]

    def __repr__(self):
        return "%s(%s)" % (type(self).__name__, ", ".join(
            "%s=%r" % (f, getattr(self, f)) for f in self._fields))


# ---- view --------------------------------------------------------------------
class View(_Struct):
    """A camera (vv_view): ``View(eye, at, up, fov=30, projection=
    "perspective", ortho_height=500, size=(512, 512))``.

    fov: vertical field of view in degrees (perspective); ortho_height:
    world height of an orthographic view; size: (width, height) pixels.
    Defaults are the library's empty World's view."""
    __slots__ = ()
    _ctype = "vv_view"
    _fields = ("eye", "at", "up", "fov", "projection", "ortho_height", "size")

    def __init__(self, eye=None, at=None, up=None, fov=None, projection=None,
                 ortho_height=None, size=None):
        self._new(dict(eye=eye, at=at, up=up, fov=fov, projection=projection,
                       ortho_height=ortho_height, size=size))

    def _init(self):
        w = ffi.new("vv_world **")
        check(lib.vv_world_new(w))
        self._c[0] = w[0].view
        lib.vv_world_free(w[0])

    eye = _vec_prop("eye", "Eye position, world units.")
    at = _vec_prop("at", "The point looked at.")
    up = _vec_prop("up", "Up direction (non-zero, not parallel to at - eye).")
    ortho_height = _num_prop("ortho_height", "World height of an orthographic view.", lo=1e-300)

    @property
    def fov(self):
        """Vertical field of view, degrees, in (0, 180)."""
        return math.degrees(self._c.fov)

    @fov.setter
    def fov(self, deg):
        deg = float(deg)
        if not 0 < deg < 180:
            raise InvalidError("fov: %r degrees is outside (0, 180)" % deg)
        self._c.fov = math.radians(deg)

    @property
    def projection(self):
        """"perspective" or "orthographic"."""
        return "orthographic" if self._c.projection == lib.VV_PROJECTION_ORTHOGRAPHIC \
            else "perspective"

    @projection.setter
    def projection(self, name):
        if name not in ("perspective", "orthographic"):
            raise InvalidError("projection: expected 'perspective' or 'orthographic', got %r"
                               % (name,))
        self._c.projection = lib.VV_PROJECTION_ORTHOGRAPHIC if name == "orthographic" \
            else lib.VV_PROJECTION_PERSPECTIVE

    @property
    def size(self):
        """(width, height) in pixels, each 1..32768."""
        return (self._c.width, self._c.height)

    @size.setter
    def size(self, wh):
        w, h = (int(wh[0]), int(wh[1]))
        if not (1 <= w <= lib.VV_IMAGE_MAX_SIDE and 1 <= h <= lib.VV_IMAGE_MAX_SIDE):
            raise InvalidError("size: %dx%d is outside 1..%d" % (w, h, lib.VV_IMAGE_MAX_SIDE))
        self._c.width, self._c.height = w, h

    def orbit(self, azimuth=0.0, elevation=0.0):
        """Moves the eye on a sphere around ``at`` by azimuth (about up) and
        elevation (towards up), degrees (vv_view_orbit). Returns self."""
        lib.vv_view_orbit(self._c, math.radians(azimuth), math.radians(elevation))
        return self

    def turn(self, azimuth=0.0, elevation=0.0, zoom=1.0):
        """The CLI's ``--azimuth --elevation --zoom`` (vv_anim_view_turn):
        orbit by the angles (degrees), then move the eye to 1/zoom of its
        distance. Returns self."""
        if not zoom > 0:
            raise InvalidError("zoom: %r is not > 0" % (zoom,))
        lib.vv_anim_view_turn(self._c, math.radians(azimuth), math.radians(elevation), zoom)
        return self

    def frame(self, box_min, box_max):
        """Points the view at the centre of the box and moves the eye along
        the viewing direction so the box's bounding sphere fits
        (vv_view_frame_box). Returns self."""
        b = ffi.new("vv_box *")
        _set_v3(b.min, box_min, "box min")
        _set_v3(b.max, box_max, "box max")
        lib.vv_view_frame_box(self._c, b[0])
        return self

    def ray(self, px, py):
        """(origin, unit direction) of the primary ray through image
        position (px + 0.5, py + 0.5), row 0 at the top (vv_view_ray)."""
        r = lib.vv_view_ray(self._c, float(px), float(py))
        return (np.array(_v3(r.origin)), np.array(_v3(r.dir)))


# ---- lights, cut planes, materials --------------------------------------------
class Light(_Struct):
    """A light (vv_light): ``Light(direction=None, position=None, color=(1,
    1, 1), intensity=1, headlight=None)``. A light with a position is a point
    light; one with a direction is directional; one with neither is a
    headlight (travels from the eye along the view direction)."""
    __slots__ = ()
    _ctype = "vv_light"
    _fields = ("type", "headlight", "direction", "position", "color", "intensity")

    def __init__(self, direction=None, position=None, color=None, intensity=None,
                 headlight=None, type=None):
        if type is None:
            type = "point" if position is not None else "directional"
        if headlight is None:
            headlight = direction is None and position is None
        self._new(dict(type=type, headlight=headlight, direction=direction, position=position,
                       color=color, intensity=intensity))

    def _init(self):
        self._c.color.x = self._c.color.y = self._c.color.z = 1.0
        self._c.intensity = 1.0
        self._c.direction.y = 1.0

    @property
    def type(self):
        """"directional" or "point"."""
        return "point" if self._c.type == lib.VV_LIGHT_POINT else "directional"

    @type.setter
    def type(self, name):
        if name not in ("directional", "point"):
            raise InvalidError("light type: expected 'directional' or 'point', got %r" % (name,))
        self._c.type = lib.VV_LIGHT_POINT if name == "point" else lib.VV_LIGHT_DIRECTIONAL

    headlight = _bool_prop("headlight", "True: directional from the eye along the view.")
    direction = _vec_prop("direction", "Directional light: the direction it travels.")
    position = _vec_prop("position", "Point light position, world units.")
    color = _vec_prop("color", "RGB in [0, 1].", color=True)
    intensity = _num_prop("intensity", "Scales color (>= 0).", lo=0)


class CutPlane(_Struct):
    """A cut plane (vv_cut_plane) keeping the half-space the normal points
    into: n . (x - point) >= 0. ``CutPlane(point, normal)``, world units."""
    __slots__ = ()
    _ctype = "vv_cut_plane"
    _fields = ("point", "normal")

    def __init__(self, point=(0, 0, 0), normal=(0, 0, 1)):
        self._new(dict(point=point, normal=normal))

    point = _vec_prop("point", "A point on the plane, world coordinates.")

    @property
    def normal(self):
        """Unit normal (normalised when set; zero is refused)."""
        return _v3(self._c.normal)

    @normal.setter
    def normal(self, value):
        n = _vec3(value, "normal")
        length = float(np.linalg.norm(n))
        if length == 0:
            raise InvalidError("cut plane normal: the zero vector has no direction")
        _set_v3(self._c.normal, n / length, "normal")


class Material(_Struct):
    """Phong material and global-illumination terms (vv_material): ambient,
    diffuse, specular, shininess, color, reflectance, transparency, ior,
    emission (docs/scene-format.md, material)."""
    __slots__ = ()
    _ctype = "vv_material"
    _fields = ("ambient", "diffuse", "specular", "shininess", "color", "reflectance",
               "transparency", "ior", "emission")

    def __init__(self, **kw):
        self._new(kw)

    def _init(self):
        o = ffi.new("vv_object **")
        check(lib.vv_object_new_geometry(o, lib.VV_OBJECT_SPHERE, ffi.NULL))
        self._c[0] = o[0].material
        lib.vv_object_free(o[0])

    ambient = _num_prop("ambient", "ka >= 0", lo=0)
    diffuse = _num_prop("diffuse", "kd >= 0", lo=0)
    specular = _num_prop("specular", "ks >= 0", lo=0)
    shininess = _num_prop("shininess", "Phong exponent >= 0", lo=0)
    color = _vec_prop("color", "Base colour, RGB in [0, 1].", color=True)
    reflectance = _num_prop("reflectance", "Fraction mirrored, [0, 1].", lo=0, hi=1)
    transparency = _num_prop("transparency", "Fraction transmitted, [0, 1].", lo=0, hi=1)
    ior = _num_prop("ior", "Index of refraction, > 0.", lo=1e-300)

    @property
    def emission(self):
        """Emitted light (radiosity), RGB each >= 0."""
        return _v3(self._c.emission)

    @emission.setter
    def emission(self, value):
        v = _vec3(value, "emission")
        if np.any(v < 0):
            raise InvalidError("emission: components must be >= 0, got %s" % (tuple(v),))
        _set_v3(self._c.emission, v, "emission")


# ---- transfer functions --------------------------------------------------------
def tf_presets():
    """The names TransferFunction.preset accepts ("ct-bone", ...)."""
    names = lib.vv_tf_preset_names()
    out = []
    i = 0
    while names[i] != ffi.NULL:
        out.append(pystr(names[i]))
        i += 1
    return out


class TransferFunction(_Struct):
    """A 1-D transfer function (vv_tf): piecewise-linear opacity and colour
    of the data value.

    ``TransferFunction(opacity=[(value, opacity), ...], color=[(value, (r, g,
    b)), ...], unit_distance=1)``; opacity and color may also be numpy arrays
    of shape (n, 2) and (n, 4) ([value, r, g, b]). Opacity is in [0, 1] per
    ``unit_distance`` world units of ray length; at most 256 points each;
    outside the first and last point the end values hold; no opacity points
    is transparent, no colour points white. Errors: InvalidError, LimitError
    with the library's message."""
    __slots__ = ()
    _ctype = "vv_tf"
    _fields = ("opacity", "color", "unit_distance")

    def __init__(self, opacity=None, color=None, unit_distance=None):
        self._new({})
        if opacity is not None:
            self.opacity = opacity
        if color is not None:
            self.color = color
        if unit_distance is not None:
            self.unit_distance = unit_distance

    def _init(self):
        lib.vv_tf_init(self._c)

    @classmethod
    def ramp(cls, lo, hi, max_opacity=1.0, color=(1, 1, 1), unit_distance=1.0):
        """Opacity 0 at ``lo`` rising linearly to ``max_opacity`` at ``hi``,
        one colour (vv_tf_set_ramp)."""
        tf = cls()
        c = ffi.new("vv_vec3 *")
        _set_v3(c, _color(color, "color"), "color")
        lib.vv_tf_set_ramp(tf._c, float(lo), float(hi), float(max_opacity), c[0],
                           float(unit_distance))
        return tf

    @classmethod
    def preset(cls, name, volume=None):
        """A preset placed on ``volume``'s values (vv_tf_preset): one of
        :func:`tf_presets` ("ct-bone", "ct-soft-tissue", "mr"). Errors:
        InvalidError (unknown name, "mr" without a volume)."""
        tf = cls()
        check(lib.vv_tf_preset(tf._c, cstr(name), ffi.NULL if volume is None else volume._ptr))
        return tf

    @classmethod
    def from_array(cls, values, rgba, unit_distance=1.0):
        """From numpy: ``values`` (n,) increasing data values and ``rgba``
        (n, 4) colours and opacities in [0, 1] at those values."""
        values = np.asarray(values, dtype=np.float64).reshape(-1)
        rgba = np.asarray(rgba, dtype=np.float64)
        if rgba.shape != (values.size, 4):
            raise InvalidError("from_array: rgba must have shape (%d, 4), got %s"
                               % (values.size, rgba.shape))
        return cls(opacity=np.column_stack([values, rgba[:, 3]]),
                   color=np.column_stack([values, rgba[:, :3]]), unit_distance=unit_distance)

    @property
    def opacity(self):
        """Opacity points as an (n, 2) float64 array of [value, opacity]."""
        c = self._c
        return np.array([(c.opacity[i].value, c.opacity[i].opacity)
                         for i in range(c.n_opacity)], dtype=np.float64).reshape(-1, 2)

    @opacity.setter
    def opacity(self, points):
        pts = np.asarray([(float(p[0]), float(p[1])) for p in points], dtype=np.float64)
        self._c.n_opacity = 0
        for v, a in pts.reshape(-1, 2):
            check(lib.vv_tf_add_opacity(self._c, v, a))

    @property
    def color(self):
        """Colour points as an (n, 4) float64 array of [value, r, g, b]."""
        c = self._c
        return np.array([(c.color[i].value, *_v3(c.color[i].color)) for i in range(c.n_color)],
                        dtype=np.float64).reshape(-1, 4)

    @color.setter
    def color(self, points):
        rows = []
        for p in points:
            if len(p) == 2:
                rows.append((float(p[0]), *[float(x) for x in p[1]]))
            else:
                rows.append(tuple(float(x) for x in p))
        self._c.n_color = 0
        col = ffi.new("vv_vec3 *")
        for r in rows:
            if len(r) != 4:
                raise InvalidError("color: expected (value, (r, g, b)) points, got %r" % (r,))
            col.x, col.y, col.z = r[1], r[2], r[3]
            check(lib.vv_tf_add_color(self._c, r[0], col[0]))

    @property
    def unit_distance(self):
        """The ray length (world units, > 0) over which opacity applies."""
        return self._c.opacity_unit_distance

    @unit_distance.setter
    def unit_distance(self, d):
        d = float(d)
        if not d > 0 or not math.isfinite(d):
            raise InvalidError("unit_distance: %r is not a finite number > 0" % d)
        self._c.opacity_unit_distance = d

    def __call__(self, values):
        """RGBA at ``values`` (any shape): float64 array of shape
        values.shape + (4,) (vv_tf_eval_color, vv_tf_eval_opacity)."""
        v = np.asarray(values, dtype=np.float64)
        out = np.empty(v.shape + (4,))
        flat = out.reshape(-1, 4)
        for n, x in enumerate(v.reshape(-1)):
            c = lib.vv_tf_eval_color(self._c, x)
            flat[n] = (c.x, c.y, c.z, lib.vv_tf_eval_opacity(self._c, x))
        return out

    def __repr__(self):
        return "TransferFunction(opacity=%s, color=%s, unit_distance=%g)" % (
            self.opacity.tolist(), self.color.tolist(), self.unit_distance)


class TransferFunction2D(_Struct):
    """A 2-D transfer function of value x gradient magnitude (vv_tf2d;
    Kniss, Kindlmann and Hansen 2002): up to 16 rectangle and triangle
    widgets combined as independent absorbers (docs/scene-format.md, tf2d).
    Used in composite mode when an object's segmentation is "tf2d"."""
    __slots__ = ()
    _ctype = "vv_tf2d"
    _fields = ("unit_distance",)

    def __init__(self, unit_distance=None):
        self._new({})
        if unit_distance is not None:
            self.unit_distance = unit_distance

    def _init(self):
        lib.vv_tf2d_init(self._c)

    unit_distance = property(TransferFunction.unit_distance.fget,
                             TransferFunction.unit_distance.fset,
                             doc="The ray length (world units) over which opacity applies.")

    def add_rectangle(self, value, gradient, color=(1, 1, 1), opacity=1.0, ramp=0.0,
                      gradient_ramp=0.0):
        """A rectangle widget over value [lo, hi] x gradient magnitude [lo,
        hi] with soft edges ``ramp`` and ``gradient_ramp``. Errors:
        InvalidError, LimitError."""
        w = ffi.new("vv_tf2d_widget *")
        c = ffi.new("vv_vec3 *")
        _set_v3(c, color, "color")
        lib.vv_tf2d_widget_init_rectangle(w, float(value[0]), float(value[1]),
                                          float(gradient[0]), float(gradient[1]), c[0],
                                          float(opacity))
        w.ramp, w.gradient_ramp = float(ramp), float(gradient_ramp)
        check(lib.vv_tf2d_add_widget(self._c, w))
        return self

    def add_triangle(self, center, width, gradient, color=(1, 1, 1), opacity=1.0):
        """Kniss's triangle widget: apex at (center, 0), base ``width`` at
        gradient magnitude gradient[1], cut below gradient[0]."""
        w = ffi.new("vv_tf2d_widget *")
        c = ffi.new("vv_vec3 *")
        _set_v3(c, color, "color")
        lib.vv_tf2d_widget_init_triangle(w, float(center), float(width), float(gradient[1]),
                                         c[0], float(opacity))
        w.gradient[0] = float(gradient[0])
        check(lib.vv_tf2d_add_widget(self._c, w))
        return self

    @property
    def widgets(self):
        """The widgets as dicts (shape, value, gradient, ramp, gradient_ramp,
        center, width, color, opacity)."""
        out = []
        for i in range(self._c.n_widgets):
            w = self._c.widgets[i]
            out.append(dict(shape="triangle" if w.shape == lib.VV_TF2D_TRIANGLE else "rectangle",
                            value=tuple(w.value), gradient=tuple(w.gradient), ramp=w.ramp,
                            gradient_ramp=w.gradient_ramp, center=w.center, width=w.width,
                            color=_v3(w.color), opacity=w.opacity))
        return out

    def __call__(self, value, gradient):
        """(opacity, (r, g, b)) at one (value, gradient magnitude)."""
        a = ffi.new("double *")
        c = ffi.new("vv_vec3 *")
        lib.vv_tf2d_eval(self._c, float(value), float(gradient), a, c)
        return a[0], _v3(c[0])


# ---- objects -----------------------------------------------------------------
_MODES = {"composite": lib.VV_MODE_COMPOSITE, "mip": lib.VV_MODE_MIP,
          "minip": lib.VV_MODE_MINIP, "xray": lib.VV_MODE_XRAY, "iso": lib.VV_MODE_ISO,
          "attenuated-mip": lib.VV_MODE_ATTENUATED_MIP}
_MODE_NAMES = {v: k for k, v in _MODES.items()}
_SEGS = {"tf": lib.VV_SEG_TRANSFER_FUNCTION, "threshold": lib.VV_SEG_THRESHOLD,
         "tf2d": lib.VV_SEG_TRANSFER_FUNCTION_2D, "labels": lib.VV_SEG_LABELS}
_SEG_NAMES = {v: k for k, v in _SEGS.items()}


def mode_code(name):
    if name not in _MODES:
        raise InvalidError("mode: expected one of %s, got %r" % (", ".join(_MODES), name))
    return _MODES[name]


class Object:
    """An object of the World (vv_object): a volume, an irregular grid or a
    geometric shape, with its transform, material, segmentation, shading
    flags and local cut planes. Made by :class:`VolumeObject`,
    :class:`GridObject`, :class:`Sphere`, :class:`Box`, :class:`Plane`,
    :class:`Cylinder`, :class:`Polygon` or :class:`MeshObject`, each taking
    these properties as keyword arguments too.

    Before ``world.add(obj)`` the Python object owns it; after, the World
    does (the object stays valid while it is in the World; ``world.remove``
    gives it back)."""
    __slots__ = ("_c", "_world", "__weakref__")

    def _setup(self, ptr, kw):
        self._c = ffi.gc(ptr, lib.vv_object_free)
        self._world = None
        for k, v in kw.items():
            if not hasattr(type(self), k) or k.startswith("_"):
                raise InvalidError("%s: unknown property %r" % (type(self).__name__, k))
            if v is not None:
                setattr(self, k, v)

    @staticmethod
    def _bound(ptr, world):
        cls = _CLASSES.get(ptr.type, Object)
        obj = cls.__new__(cls)
        obj._c = ptr
        obj._world = world
        return obj

    @property
    def type(self):
        """The object's type as in scene files ("volume", "sphere", ...)."""
        return pystr(lib.vv_object_type_name(self._c.type))

    @property
    def name(self):
        """Name (< 64 bytes)."""
        return ffi.string(self._c.name).decode("utf-8", "replace")

    @name.setter
    def name(self, value):
        b = cstr(value)
        if len(b) >= lib.VV_NAME_MAX:
            raise InvalidError("name: %r is %d bytes, at most %d" % (value, len(b),
                                                                     lib.VV_NAME_MAX - 1))
        self._c.name = b

    position = _vec_prop("position", "Translation of the object, world units.")
    scale = _vec_prop("scale", "Scale factors along x, y, z (> 0).")

    @property
    def orientation(self):
        """Rotation as a unit quaternion (w, x, y, z) (normalised when set)."""
        q = self._c.orientation
        return (q.w, q.x, q.y, q.z)

    @orientation.setter
    def orientation(self, q):
        q = np.asarray(q, dtype=np.float64).reshape(-1)
        if q.shape != (4,) or not np.all(np.isfinite(q)) or not np.any(q):
            raise InvalidError("orientation: expected a non-zero quaternion (w, x, y, z)")
        q = q / np.linalg.norm(q)
        o = self._c.orientation
        o.w, o.x, o.y, o.z = (float(x) for x in q)

    def rotate(self, axis, degrees):
        """Turns the object by ``degrees`` about ``axis`` (world axes,
        right-handed), after its current orientation. Returns self."""
        a = ffi.new("vv_vec3 *")
        _set_v3(a, axis, "axis")
        r = lib.vv_quat_from_axis_angle(a[0], math.radians(degrees))
        self._c.orientation = lib.vv_quat_normalize(lib.vv_quat_mul(r, self._c.orientation))
        return self

    def matrix(self):
        """4x4 object-to-world matrix T(position) R(orientation) S(scale)."""
        return _mat4(lib.vv_object_matrix(self._c))

    def world_box(self):
        """(min, max) of the object's world bounding box."""
        b = lib.vv_object_world_box(self._c)
        return (np.array(_v3(b.min)), np.array(_v3(b.max)))

    @property
    def material(self):
        """The Material, read and written in place."""
        return Material._at(ffi.addressof(self._c, "material"), self)

    @material.setter
    def material(self, m):
        if isinstance(m, dict):
            m = Material(**m)
        self._c.material = m._value()

    @property
    def mode(self):
        """"composite", "mip", "minip", "xray", "iso" or "attenuated-mip"
        (napari's attenuated MIP, drawn by raycast and gpu; see
        ``attenuation``)."""
        return _MODE_NAMES.get(self._c.mode, "composite")

    @mode.setter
    def mode(self, name):
        self._c.mode = mode_code(name)

    @property
    def segmentation(self):
        """"tf" (transfer function), "threshold", "tf2d" or "labels"."""
        return _SEG_NAMES.get(self._c.segmentation, "tf")

    @segmentation.setter
    def segmentation(self, name):
        if name not in _SEGS:
            raise InvalidError("segmentation: expected one of %s, got %r" % (", ".join(_SEGS),
                                                                            name))
        self._c.segmentation = _SEGS[name]

    @property
    def tf(self):
        """The TransferFunction, read and written in place."""
        return TransferFunction._at(ffi.addressof(self._c, "tf"), self)

    @tf.setter
    def tf(self, tf):
        self._c.tf = tf._value()

    @property
    def tf2d(self):
        """The TransferFunction2D, read and written in place."""
        return TransferFunction2D._at(ffi.addressof(self._c, "tf2d"), self)

    @tf2d.setter
    def tf2d(self, tf):
        self._c.tf2d = tf._value()

    threshold = _num_prop("threshold", "Threshold segmentation: opaque where value >= it.")
    isovalue = _num_prop("isovalue", "Iso mode: the isovalue.")
    attenuation = _num_prop("attenuation", "Attenuated-mip mode: napari's attenuation (>= 0, "
                            "default 0.05; 0 gives MIP).", lo=0)
    step = _num_prop("step", "Sample step in units of the smallest voxel spacing (> 0).",
                     lo=1e-6)
    shading = _bool_prop("shading", "Phong shading from gradients (False: emission only).")
    visible = _bool_prop("visible", "Hidden objects are kept but not drawn.")
    casts_shadows = _bool_prop("casts_shadows", "Blocks light on its way to other points.")
    receives_shadows = _bool_prop("receives_shadows", "Shaded with shadow rays.")
    visible_in_reflections = _bool_prop("visible_in_reflections",
                                        "Seen by reflected and transmitted rays.")
    reflects = _bool_prop("reflects", "Spawns reflected rays where reflectance > 0.")

    @property
    def cut_planes(self):
        """Local cut planes (world coordinates): a list of CutPlane proxies;
        assign a list of CutPlane or (point, normal) pairs to replace them."""
        return [CutPlane._at(ffi.addressof(self._c.cut_planes, i), self)
                for i in range(self._c.n_cut_planes)]

    @cut_planes.setter
    def cut_planes(self, planes):
        planes = [p if isinstance(p, CutPlane) else CutPlane(*p) for p in planes]
        if len(planes) > lib.VV_MAX_CUT_PLANES:
            raise InvalidError("cut_planes: %d planes, at most %d" % (len(planes),
                                                                      lib.VV_MAX_CUT_PLANES))
        for i, p in enumerate(planes):
            self._c.cut_planes[i] = p._value()
        self._c.n_cut_planes = len(planes)

    def set_texture(self, path, projection="planar", center=(0, 0, 0), axis=(0, 0, 1),
                    scale=(1, 1)):
        """An image texture (PNG) on the object (docs/scene-format.md,
        texture): projection "planar", "cylindrical" or "spherical", in object
        coordinates. ``path=None`` removes it. Errors: FileError, FormatError."""
        if path is None:
            lib.vv_object_set_texture_image(self._c, ffi.NULL)
            return self
        t = ffi.new("vv_texture_image **")
        check(lib.vv_texture_image_load(t, cstr(path), cstr(os.fspath(path))))
        lib.vv_object_set_texture_image(self._c, t[0])
        lib.vv_texture_image_free(t[0])
        p = ffi.new("vv_texture_projection *")
        check(lib.vv_texture_projection_parse(cstr(projection), p))
        m = self._c.texture
        m.projection = p[0]
        _set_v3(m.center, center, "center")
        _set_v3(m.axis, np.asarray(_vec3(axis, "axis")) / np.linalg.norm(axis), "axis")
        m.scale[0], m.scale[1] = float(scale[0]), float(scale[1])
        return self

    def __repr__(self):
        return "<volvis.%s %r>" % (type(self).__name__, self.name)


def _geom_vec(field, doc):
    def get(self):
        return _v3(getattr(self._c.geometry, field))

    def set_(self, value):
        _set_v3(getattr(self._c.geometry, field), value, field)
    return property(get, set_, doc=doc)


def _geom_num(field, doc):
    def get(self):
        return getattr(self._c.geometry, field)

    def set_(self, value):
        v = float(value)
        if not v > 0:
            raise InvalidError("%s: %r is not > 0" % (field, value))
        setattr(self._c.geometry, field, v)
    return property(get, set_, doc=doc)


def _new_geometry(type_code, name):
    out = ffi.new("vv_object **")
    check(lib.vv_object_new_geometry(out, type_code, cstr(name)))
    return out[0]


class VolumeObject(Object):
    """``VolumeObject(volume, name=None, **properties)``: a volume in the
    World (vv_object_new_volume: composite mode, step 0.5, shading on, a
    white ramp transfer function over the volume's range)."""
    __slots__ = ()

    def __init__(self, volume, name=None, **kw):
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        out = ffi.new("vv_object **")
        check(lib.vv_object_new_volume(out, volume._ptr, cstr(name)))
        self._setup(out[0], kw)

    @property
    def volume(self):
        """The Volume shown (shared with the object, not copied)."""
        return Volume._borrow(self._c.volume)

    @property
    def source(self):
        """The file the volume came from (scene saving), or None."""
        s = self._c.geometry.source
        return None if s == ffi.NULL else pystr(s)


class GridObject(Object):
    """``GridObject(grid, field=None, name=None, **properties)``: an
    irregular grid showing ``field`` (vv_object_new_grid)."""
    __slots__ = ()

    def __init__(self, grid, field=None, name=None, **kw):
        out = ffi.new("vv_object **")
        check(lib.vv_object_new_grid(out, grid._ptr, cstr(field), cstr(name)))
        self._setup(out[0], kw)

    @property
    def field(self):
        """Name of the field shown ("" = the first)."""
        return ffi.string(self._c.field).decode()

    @field.setter
    def field(self, name):
        self._c.field = cstr(name)

    component = _num_prop("component", "Vector component shown, -1 the magnitude.", lo=-1,
                          integer=True)
    time = _num_prop("time", "Time step.", lo=0, integer=True)


class Sphere(Object):
    """``Sphere(center=(0, 0, 0), radius=1, name=None, **properties)``."""
    __slots__ = ()

    def __init__(self, center=None, radius=None, name=None, **kw):
        self._setup(_new_geometry(lib.VV_OBJECT_SPHERE, name),
                    dict(center=center, radius=radius, **kw))

    center = _geom_vec("center", "Centre, object coordinates.")
    radius = _geom_num("radius", "Radius > 0.")


class Box(Object):
    """``Box(min=(-1, -1, -1), max=(1, 1, 1), name=None, **properties)``."""
    __slots__ = ()

    def __init__(self, min=None, max=None, name=None, **kw):
        self._setup(_new_geometry(lib.VV_OBJECT_BOX, name), kw)
        if min is not None:
            _set_v3(self._c.geometry.box.min, min, "min")
        if max is not None:
            _set_v3(self._c.geometry.box.max, max, "max")

    @property
    def box(self):
        """(min, max) corners in object coordinates."""
        b = self._c.geometry.box
        return (_v3(b.min), _v3(b.max))


class Plane(Object):
    """``Plane(point=(0, 0, 0), normal=(0, 0, 1), name=None, **properties)``:
    an infinite plane facing ``normal``."""
    __slots__ = ()

    def __init__(self, point=None, normal=None, name=None, **kw):
        self._setup(_new_geometry(lib.VV_OBJECT_PLANE, name), dict(point=point, **kw))
        if normal is not None:
            n = _vec3(normal, "normal")
            _set_v3(self._c.geometry.normal, n / np.linalg.norm(n), "normal")

    point = _geom_vec("point", "A point on the plane, object coordinates.")

    @property
    def normal(self):
        """Unit normal (its front side)."""
        return _v3(self._c.geometry.normal)


class Cylinder(Object):
    """``Cylinder(base=(0, 0, -1), top=(0, 0, 1), radius=1, capped=True,
    name=None, **properties)``."""
    __slots__ = ()

    def __init__(self, base=None, top=None, radius=None, capped=None, name=None, **kw):
        self._setup(_new_geometry(lib.VV_OBJECT_CYLINDER, name),
                    dict(base=base, top=top, radius=radius, **kw))
        if capped is not None:
            self._c.geometry.capped = 1 if capped else 0

    base = _geom_vec("base", "Centre of the base disc.")
    top = _geom_vec("top", "Centre of the top disc.")
    radius = _geom_num("radius", "Radius > 0.")


class Polygon(Object):
    """``Polygon(vertices, name=None, **properties)``: a planar polygon of
    n >= 3 vertices, an (n, 3) array (vv_object_set_polygon)."""
    __slots__ = ()

    def __init__(self, vertices, name=None, **kw):
        self._setup(_new_geometry(lib.VV_OBJECT_POLYGON, name), kw)
        self.vertices = vertices

    @property
    def vertices(self):
        """(n, 3) float64 array of the vertices."""
        g = self._c.geometry
        return np.array([_v3(g.vertices[i]) for i in range(g.n_vertices)]).reshape(-1, 3)

    @vertices.setter
    def vertices(self, value):
        v = np.asarray(value, dtype=np.float64).reshape(-1, 3)
        buf = ffi.new("vv_vec3[]", len(v))
        for i, p in enumerate(v):
            buf[i].x, buf[i].y, buf[i].z = p
        check(lib.vv_object_set_polygon(self._c, len(v), buf))


class MeshObject(Object):
    """``MeshObject(mesh, name=None, **properties)``: a triangle mesh, a
    :class:`volvis.Mesh` or a ``(vertices, triangles)`` pair of arrays."""
    __slots__ = ()

    def __init__(self, mesh, name=None, source=None, **kw):
        from .mesh import Mesh
        if not isinstance(mesh, Mesh):
            mesh = Mesh(*mesh)
        self._setup(_new_geometry(lib.VV_OBJECT_MESH, name), kw)
        check(lib.vv_object_set_mesh(self._c, mesh._ptr, cstr(source)))

    @property
    def mesh(self):
        """The Mesh drawn (shared)."""
        from .mesh import Mesh
        return Mesh._own(lib.vv_mesh_ref(self._c.geometry.mesh))


_CLASSES = {lib.VV_OBJECT_VOLUME: VolumeObject, lib.VV_OBJECT_SPHERE: Sphere,
            lib.VV_OBJECT_BOX: Box, lib.VV_OBJECT_PLANE: Plane,
            lib.VV_OBJECT_CYLINDER: Cylinder, lib.VV_OBJECT_POLYGON: Polygon,
            lib.VV_OBJECT_MESH: MeshObject, lib.VV_OBJECT_GRID: GridObject}


# ---- world -------------------------------------------------------------------
class _Objects:
    """The objects of a World as a sequence (``world.objects``)."""
    __slots__ = ("_w",)

    def __init__(self, world):
        self._w = world

    def __len__(self):
        return self._w._c.n_objects

    def __getitem__(self, i):
        n = len(self)
        if isinstance(i, str):
            for k in range(n):
                if ffi.string(self._w._c.objects[k].name).decode() == i:
                    return self._w._proxy(k)
            raise KeyError(i)
        if isinstance(i, slice):
            return [self[k] for k in range(n)[i]]
        if i < 0:
            i += n
        if not 0 <= i < n:
            raise IndexError("object index %d out of range (%d objects)" % (i, n))
        return self._w._proxy(i)

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def __repr__(self):
        return repr(list(self))


class World:
    """A World (vv_world): view, lights, objects, global cut planes, ambient
    light, background colour and render settings.

    ``World()`` is empty (a 512x512 view from (0, -1000, 0), no lights).
    :meth:`open` opens what a user names (a volume file, a folder, a store,
    a scene, a grid) into the World ``volvis render WHAT`` draws;
    :meth:`for_volume` builds the scene ``volvis render FILE`` builds of a
    Volume in memory; :func:`load_scene` reads a scene file."""
    __slots__ = ("_c", "_proxies", "_opened", "__weakref__")

    def __init__(self):
        out = ffi.new("vv_world **")
        check(lib.vv_world_new(out))
        self._set(out[0])

    def _set(self, ptr):
        self._c = ffi.gc(ptr, lib.vv_world_free)
        self._proxies = weakref.WeakValueDictionary()
        self._opened = None

    @classmethod
    def _own(cls, ptr):
        w = cls.__new__(cls)
        w._set(ptr)
        return w

    @classmethod
    def open(cls, what, *, channel=None, time=None, series=None, level=None, memory=None,
             memory_limit=None, lod=False, channels=None, colors=None, contrast=None,
             blend=None, labels=False, mode=None, tf=None, iso=None, size=None, renderer=None,
             step=None, field=None, format=None, raw=None, slice_window=False, progress=None):
        """The World ``volvis render WHAT`` draws, through the library's one
        door (vv_world_open, docs/python.md "World.open"): ``what`` (a str or
        path) names a volume file, a folder (a DICOM series, a TIFF stack, an
        OME-Zarr store), a scene file (``.json``), a BigDataViewer XML or an
        irregular grid. The input is opened once; a volume becomes the
        default scene (centred, framed from the front, a headlight, a
        transfer function from the data), in memory or out of core; a scene
        is loaded with its files; a grid gets its default scene. The view is
        fitted, not turned.

        Which data: channel, time, series (None: the file's first; channel
        and time 0-based, series 1-based as ``volvis info`` lists them);
        level: a multiresolution file's level (0 the finest; None: none
        given); format ("nrrd", ... as :func:`volvis.open`) and raw (a dict
        as :func:`volvis.open`'s) for raw files; field: a grid's field (None:
        its first scalar field).

        Where it lives: memory None or "auto" (read whole, unless rendering
        it in memory would take more than the memory budget: then out of
        core where the file can be, said in ``opened["switched"]``),
        "out_of_core" (a file that cannot be read so raises
        UnsupportedError) or "out_of_core_if_able"; memory_limit: the
        process cache's budget in bytes, or text such as "512M" (None: keep
        :func:`volvis.memory_limit`'s); lod: True to read a pyramid by its
        levels (level of detail; :func:`volvis.render`'s ``lod`` and
        ``level`` then pick them), out of core unless ``memory`` says
        otherwise (a file read whole only then raises UnsupportedError,
        one read by bricks without levels InvalidError).

        Channels: channels a list of the file's channel indices shown as one
        object of several channels, or "all" (every channel, in order);
        colors a list of (r, g, b) in [0, 1], contrast a list of (lo, hi)
        data values, blend "composite", "additive" or "maximum", for them
        (a scene, or more colours than the file has channels, raises
        InvalidError). Without channel, channels, mode, tf, iso or labels a
        file of several channels shows them all (its active ones visible, in
        their colours, with the contrast of their omero windows, else of
        the coarsest level), in memory or out of core alike: a pyramid out
        of core reads every channel of a node at once.

        Overrides of the guessed appearance: mode ("composite", "mip",
        "minip", "xray", "iso", "attenuated-mip"), tf (lo, hi) the transfer function's data
        range (a scene's stretched onto it), iso the isovalue, size
        (width, height) pixels of the view, renderer the method that will
        draw it (the automatic out-of-core switch needs one with the region
        contract; None: raycast; it is not stored in the World: pass it to
        :func:`volvis.render`), step every object's sample step (in units
        of the smallest spacing, > 0), labels True: every volume object a
        label volume. slice_window: True to guess the slice views' window
        and level of the first volume (``opened["slice_window"]``).
        progress: as :func:`volvis.render` (a scene's geometry voxelized).

        Returns a new :class:`World` that owns its objects (a file read out
        of core stays open while the World lives; its pieces live in the
        process cache). ``world.opened`` says what the door found: a dict of
        "input" ("volume", "grid" or "scene"), "n_channels" and "n_times"
        (of the volume file; 1 for a scene or a grid), "out_of_core"
        (a visible object shows a file out of core), "switched" with
        "need_bytes", "budget_bytes" and "cache_bytes" (the automatic switch
        to out of core), and "slice_window" ((window, level) in data values
        with ``slice_window=True``, else None).

        Thread-safe, but for the process cache's budget it sets (the
        process's). Errors: FileError (missing, unreadable), FormatError
        (cannot tell the format, malformed), UnsupportedError (out of core
        of a file that cannot be), InvalidError (options that do not fit
        the input, a channel, time step or level past the file's), LimitError,
        NoMemoryError, with the library's one-line message naming ``what``;
        KeyboardInterrupt or CancelledError as :func:`volvis.render`."""
        from . import _lib
        from .pyramid import _bytes
        from .volume import _raw_params
        o = ffi.new("vv_world_open_options *")
        lib.vv_world_open_options_init(o)
        if channel is not None:
            o.load.channel = int(channel)
        if time is not None:
            o.load.time = int(time)
        if series is not None:
            o.load.series = int(series)
        if format is not None:
            f = ffi.new("vv_format *")
            check(lib.vv_format_parse(cstr(format), f))
            o.load.format = f[0]
        if raw is not None:
            o.load.has_raw = 1
            o.load.format = lib.VV_FORMAT_RAW
            _raw_params(o.load.raw, raw)
        if level is not None:
            if int(level) < 0:
                raise InvalidError("World.open: level %r is < 0" % (level,))
            o.level = int(level)
        if memory not in _MEMORY:
            raise InvalidError("World.open: memory: expected one of %s, got %r"
                               % (", ".join(repr(k) for k in _MEMORY if k), memory))
        if memory is None and lod:
            memory = "out_of_core"  # as volvis render --lod
        o.memory = _MEMORY[memory]
        o.memory_limit = _bytes(memory_limit) if memory_limit is not None else \
            int(lib.vv_cache_limit(lib.vv_cache_process()))
        o.levels = 1 if lod else 0
        keep = []  # the C strings the options point to, alive through the call
        if renderer is not None:
            keep.append(ffi.new("char[]", cstr(renderer)))
            o.renderer = keep[-1]
        if field is not None:
            keep.append(ffi.new("char[]", cstr(field)))
            o.field = keep[-1]
        _open_channels(o, channels, colors, contrast, blend)
        if channels is None and channel is None and mode is None and tf is None and \
                iso is None and not labels:
            o.all_channels = 1  # a file of several channels: all of them, in their colours
        if mode is not None:
            o.has_mode = 1
            o.view.mode = mode_code(mode)
        if tf is not None:
            lo, hi = float(tf[0]), float(tf[1])
            if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
                raise InvalidError("World.open: tf (%r, %r): expected finite lo < hi" % (lo, hi))
            o.view.has_tf_range = 1
            o.view.tf_lo, o.view.tf_hi = lo, hi
        if iso is not None:
            o.view.has_isovalue = 1
            o.view.isovalue = float(iso)
        if size is not None:
            w, h = int(size[0]), int(size[1])
            if not (1 <= w <= lib.VV_IMAGE_MAX_SIDE and 1 <= h <= lib.VV_IMAGE_MAX_SIDE):
                raise InvalidError("World.open: size %dx%d is outside 1..%d"
                                   % (w, h, lib.VV_IMAGE_MAX_SIDE))
            o.has_size = 1
            o.view.width, o.view.height = w, h
        if step is not None:
            if not float(step) > 0:
                raise InvalidError("World.open: step %r is not > 0" % (step,))
            o.step = float(step)
        o.labels = 1 if labels else 0
        o.slice_window = 1 if slice_window else 0
        out = ffi.new("vv_world **")
        info = ffi.new("vv_world_open_info *")
        p = cstr(what)
        holder = {}

        def run(prog):
            holder["p"] = ffi.new("vv_progress *", prog)
            o.progress = holder["p"]
            return lib.vv_world_open(out, p, o, info)
        _lib.call_long(run, progress, desc="open")
        w = cls._own(out[0])
        w._opened = {
            "input": _INPUT_NAMES.get(info.input, "volume"),
            "n_channels": int(info.n_channels), "n_times": int(info.n_times),
            "out_of_core": bool(info.out_of_core), "switched": bool(info.switched),
            "need_bytes": int(info.need_bytes), "budget_bytes": int(info.budget_bytes),
            "cache_bytes": int(info.cache_bytes),
            "slice_window": (info.window, info.level) if slice_window else None,
        }
        return w

    @property
    def opened(self):
        """What :meth:`World.open` found and decided (a dict: input,
        n_channels, n_times, out_of_core, switched, need_bytes,
        budget_bytes, cache_bytes, slice_window), or None for a World made
        otherwise (a clone too)."""
        return None if self._opened is None else dict(self._opened)

    @classmethod
    def for_volume(cls, volume, mode="composite", tf_range=None, isovalue=None, size=None,
                   azimuth=0.0, elevation=0.0, zoom=1.0):
        """The default scene of ``volvis render FILE`` (vv_world_new_for_volume,
        docs/scene-format.md "Default scene"): the volume centred, a view from
        the front framing it, a headlight, and a transfer function from the
        histogram (or ``tf_range`` (lo, hi)). ``volume`` is a Volume or an
        array (shared as by Volume()); angles in degrees."""
        if not isinstance(volume, Volume):
            volume = Volume(volume)
        o = _scene_options(mode, tf_range, isovalue, size, azimuth, elevation, zoom)
        out = ffi.new("vv_world **")
        check(lib.vv_world_new_for_volume(out, volume._ptr, o))
        return cls._own(out[0])

    @classmethod
    def for_grid(cls, grid, field=None, time=0, mode="composite", tf_range=None, isovalue=None,
                 size=None, azimuth=0.0, elevation=0.0, zoom=1.0):
        """The default scene of ``volvis render GRIDFILE`` (vv_world_new_for_grid)."""
        o = _scene_options(mode, tf_range, isovalue, size, azimuth, elevation, zoom)
        out = ffi.new("vv_world **")
        check(lib.vv_world_new_for_grid(out, grid._ptr, cstr(field), int(time), o))
        return cls._own(out[0])

    def _proxy(self, i):
        ptr = self._c.objects[i]
        key = int(ffi.cast("uintptr_t", ptr))
        obj = self._proxies.get(key)
        if obj is None:
            obj = Object._bound(ptr, self)
            self._proxies[key] = obj
        return obj

    # ---- objects
    @property
    def objects(self):
        """The objects, a sequence indexable by position or name."""
        return _Objects(self)

    def add(self, obj):
        """Appends an object (the World takes it over) and returns it."""
        return self.insert(len(self.objects), obj)

    def insert(self, index, obj):
        """Inserts an object at ``index`` (the World takes it over); returns it."""
        if not isinstance(obj, Object):
            raise InvalidError("World.add: expected a volvis Object, got %s"
                               % type(obj).__name__)
        if obj._world is not None:
            raise InvalidError("World.add: object %r is already in a World" % obj.name)
        raw = ffi.cast("vv_object *", obj._c)
        ffi.gc(obj._c, None)  # the World owns it now (and frees it on failure)
        obj._c = raw
        st = lib.vv_world_insert_object(self._c, int(index), raw)
        if st != 0:
            obj._c = ffi.NULL
            check(st)
        obj._world = self
        self._proxies[int(ffi.cast("uintptr_t", raw))] = obj
        return obj

    def remove(self, obj):
        """Removes an object (by Object, index or name) and returns it, now
        owned by Python again."""
        if isinstance(obj, Object):
            idx = next((i for i in range(self._c.n_objects) if self._c.objects[i] == obj._c),
                       None)
            if idx is None:
                raise InvalidError("World.remove: the object is not in this World")
        elif isinstance(obj, str):
            idx = next((i for i in range(self._c.n_objects)
                        if ffi.string(self._c.objects[i].name).decode() == obj), None)
            if idx is None:
                raise InvalidError("World.remove: no object named %r" % obj)
        else:
            idx = int(obj)
        proxy = self._proxy(idx)
        out = ffi.new("vv_object **")
        check(lib.vv_world_take_object(self._c, idx, out))
        self._proxies.pop(int(ffi.cast("uintptr_t", out[0])), None)
        proxy._c = ffi.gc(out[0], lib.vv_object_free)
        proxy._world = None
        return proxy

    # ---- lights and cut planes
    @property
    def lights(self):
        """The lights as Light proxies (read and written in place)."""
        return [Light._at(ffi.addressof(self._c.lights, i), self)
                for i in range(self._c.n_lights)]

    def add_light(self, light=None, **kw):
        """Appends a copy of ``light`` (or ``Light(**kw)``); returns the
        World's Light. Errors: LimitError beyond 16 lights."""
        light = light if light is not None else Light(**kw)
        check(lib.vv_world_add_light(self._c, light._c))
        return self.lights[-1]

    def clear_lights(self):
        """Removes every light."""
        self._c.n_lights = 0

    @property
    def cut_planes(self):
        """Global cut planes as CutPlane proxies."""
        return [CutPlane._at(ffi.addressof(self._c.cut_planes, i), self)
                for i in range(self._c.n_cut_planes)]

    def add_cut_plane(self, point, normal):
        """Appends a global cut plane keeping n . (x - point) >= 0. Errors:
        LimitError beyond 8, InvalidError for a zero normal."""
        p, n = ffi.new("vv_vec3 *"), ffi.new("vv_vec3 *")
        _set_v3(p, point, "point")
        _set_v3(n, normal, "normal")
        check(lib.vv_world_add_cut_plane(self._c, p[0], n[0]))
        return self.cut_planes[-1]

    def clear_cut_planes(self):
        """Removes every global cut plane."""
        self._c.n_cut_planes = 0

    # ---- view and shading
    @property
    def view(self):
        """The World's View, read and written in place."""
        return View._at(ffi.addressof(self._c, "view"), self)

    @view.setter
    def view(self, v):
        self._c.view = v._value()

    ambient = _vec_prop("ambient", "Global ambient light colour.", color=True)
    background = _vec_prop("background", "Background colour.", color=True)

    # ---- render settings
    @property
    def renderer(self):
        """The renderer the World asks for (scene "render" section), or None."""
        s = ffi.string(self._c.render.renderer).decode()
        return s or None

    @renderer.setter
    def renderer(self, name):
        b = cstr(name or "")
        if len(b) >= lib.VV_RENDER_NAME_MAX:
            raise InvalidError("renderer: name %r is too long" % name)
        self._c.render.renderer = b

    @property
    def quality(self):
        """The quality level 0..2 the World asks for, or None."""
        q = self._c.render.quality
        return None if q < 0 else q

    @quality.setter
    def quality(self, q):
        if q is not None and int(q) not in (0, 1, 2):
            raise InvalidError("quality: expected 0, 1 or 2, got %r" % (q,))
        self._c.render.quality = -1 if q is None else int(q)

    @property
    def render_options(self):
        """The renderer options of the render settings, {key: text} (a copy;
        change them with :meth:`set_render_option`)."""
        r = self._c.render
        return {ffi.string(r.option_keys[i]).decode(): ffi.string(r.option_values[i]).decode()
                for i in range(r.n_options)}

    def set_render_option(self, key, value):
        """Sets a render-settings option (kept in saved scenes; checked by
        the renderer at render time)."""
        from .render import option_text
        check(lib.vv_render_settings_set_option(ffi.addressof(self._c, "render"), cstr(key),
                                                cstr(option_text(value))))

    # ---- whole World
    def bounds(self):
        """(min, max) world bounding box of the visible bounded objects."""
        b = lib.vv_world_bounds(self._c)
        return (np.array(_v3(b.min)), np.array(_v3(b.max)))

    def clone(self):
        """A snapshot (vv_world_clone): objects copied, voxels shared."""
        out = ffi.new("vv_world **")
        check(lib.vv_world_clone(out, self._c))
        return World._own(out[0])

    def save(self, path, volume_files=None, write_volumes=False):
        """Writes the World as a scene file, atomically (vv_scene_save).

        volume_files: for each object, the file its volume is referred to by
        (relative to the scene file), or None to use the file it was loaded
        from. write_volumes: volumes that came from no file (made in numpy)
        are first written beside the scene as ``<scene>_<object>.nrrd``.
        Errors: FileError, InvalidError (a volume with no file)."""
        path = os.fspath(path)
        n = self._c.n_objects
        names = list(volume_files) if volume_files is not None else [None] * n
        if len(names) != n:
            raise InvalidError("World.save: %d volume_files for %d objects" % (len(names), n))
        if write_volumes:
            stem = os.path.splitext(path)[0]
            for i in range(n):
                o = self._c.objects[i]
                if o.type == lib.VV_OBJECT_VOLUME and names[i] is None and \
                        o.geometry.source == ffi.NULL:
                    name = ffi.string(o.name).decode() or "volume%d" % i
                    f = "%s_%s.nrrd" % (stem, "".join(c if c.isalnum() else "_" for c in name))
                    check(lib.vv_volume_save(o.volume, cstr(f), lib.VV_FORMAT_NRRD, 1))
                    names[i] = os.path.basename(f)
        for i in range(n):
            o = self._c.objects[i]
            if o.type == lib.VV_OBJECT_VOLUME and names[i] is None and \
                    o.geometry.source == ffi.NULL:
                raise InvalidError("World.save: %s: object %d (%s) has no volume file; pass "
                                   "volume_files or write_volumes=True" % (
                                       path, i, ffi.string(o.name).decode()))
        keep = [ffi.new("char[]", cstr(s)) if s is not None else ffi.NULL for s in names]
        arr = ffi.new("const char *[]", keep) if n else ffi.NULL
        check(lib.vv_scene_save(self._c, cstr(path), arr))

    def __repr__(self):
        return "<volvis.World %d objects, %d lights, view %dx%d>" % (
            self._c.n_objects, self._c.n_lights, self._c.view.width, self._c.view.height)

    def _repr_png_(self):
        from .notebook import png_bytes
        from .render import render
        return png_bytes(render(self))


_MEMORY = {None: lib.VV_WORLD_MEMORY_AUTO, "auto": lib.VV_WORLD_MEMORY_AUTO,
           "out_of_core": lib.VV_WORLD_OUT_OF_CORE,
           "out_of_core_if_able": lib.VV_WORLD_OUT_OF_CORE_IF_ABLE}
_INPUT_NAMES = {lib.VV_INPUT_VOLUME: "volume", lib.VV_INPUT_GRID: "grid",
                lib.VV_INPUT_SCENE: "scene"}
_BLENDS = {"composite": lib.VV_BLEND_COMPOSITE, "additive": lib.VV_BLEND_ADDITIVE,
           "maximum": lib.VV_BLEND_MAXIMUM}


def _open_channels(o, channels, colors, contrast, blend):
    """World.open's channels, colours, contrast and blend into the options."""
    n_max = lib.VV_MAX_CHANNELS
    if isinstance(channels, str):
        if channels != "all":
            raise InvalidError("World.open: channels: expected a list of ints or 'all', got %r"
                               % (channels,))
        o.all_channels = 1
    elif channels is not None:
        idx = [int(c) for c in channels]
        if not 1 <= len(idx) <= n_max or any(c < 0 for c in idx):
            raise InvalidError("World.open: channels %r: 1 to %d indices, each >= 0"
                               % (list(channels), n_max))
        o.n_channels = len(idx)
        for i, c in enumerate(idx):
            o.channels[i] = c
    elif colors is not None or contrast is not None or blend is not None:
        o.all_channels = 1  # colours, contrast or a blend rule: every channel of the file
    if colors is not None:
        cols = [_color(c, "colors[%d]" % i) for i, c in enumerate(colors)]
        if len(cols) > n_max:
            raise InvalidError("World.open: %d colors, at most %d" % (len(cols), n_max))
        o.n_colors = len(cols)
        for i, c in enumerate(cols):
            _set_v3(o.colors[i], c, "colors[%d]" % i)
    if contrast is not None:
        lims = [(float(a), float(b)) for a, b in contrast]
        if len(lims) > n_max:
            raise InvalidError("World.open: %d contrast limits, at most %d" % (len(lims), n_max))
        o.n_contrast = len(lims)
        for i, (a, b) in enumerate(lims):
            o.contrast[i][0], o.contrast[i][1] = a, b
    if blend is not None:
        if blend not in _BLENDS:
            raise InvalidError("World.open: blend: expected one of %s, got %r"
                               % (", ".join(_BLENDS), blend))
        o.has_blend = 1
        o.blend = _BLENDS[blend]


def _scene_options(mode, tf_range, isovalue, size, azimuth, elevation, zoom):
    o = ffi.new("vv_default_scene_options *")
    lib.vv_default_scene_options_init(o)
    o.mode = mode_code(mode or "composite")
    if tf_range is not None:
        o.has_tf_range = 1
        o.tf_lo, o.tf_hi = float(tf_range[0]), float(tf_range[1])
    if isovalue is not None:
        o.has_isovalue = 1
        o.isovalue = float(isovalue)
    if size is not None:
        o.width, o.height = int(size[0]), int(size[1])
    o.azimuth, o.elevation, o.zoom = math.radians(azimuth), math.radians(elevation), float(zoom)
    return o


def load_scene(path, progress=None):
    """Loads a scene file (vv_scene_load_progress; docs/scene-format.md) into
    a World; volume files are resolved relative to it and geometry objects
    voxelized (``progress`` reports that). Errors: FileError, LimitError,
    FormatError with file:line:column and the key path, or a volume file's
    error."""
    from . import _lib
    out = ffi.new("vv_world **")
    p = cstr(path)
    holder = {}

    def run(prog):
        holder["p"] = ffi.new("vv_progress *", prog)
        return lib.vv_scene_load_progress(out, p, holder["p"])
    _lib.call_long(run, progress, desc="scene")
    return World._own(out[0])
