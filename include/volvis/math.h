/*
 * VolVis math: vectors, 4x4 matrices, quaternions, rays, boxes and planes.
 *
 * Conventions (stated once, here):
 *  - All types are small transparent structs passed by value, in double.
 *  - vv_mat4 is ROW-MAJOR, m[row][col], and acts on COLUMN vectors:
 *    p' = M p, so M = A * B applies B first. Translation sits in m[0..2][3].
 *  - Angles are radians inside the library (degrees only in files and on the
 *    command line).
 *  - Right-handed coordinates. Camera space looks down -z with +y up.
 *
 * Thread-safety: all functions are pure and reentrant.
 */
#ifndef VOLVIS_MATH_H
#define VOLVIS_MATH_H

#ifdef __cplusplus
extern "C" {
#endif

#define VV_PI 3.14159265358979323846

typedef struct vv_vec3 {
    double x, y, z;
} vv_vec3;

/** Row-major 4x4 matrix acting on column vectors (see the file comment). */
typedef struct vv_mat4 {
    double m[4][4];
} vv_mat4;

/** Unit quaternion w + xi + yj + zk for rotations. */
typedef struct vv_quat {
    double w, x, y, z;
} vv_quat;

/** Ray origin + t * dir; dir need not be unit unless a function says so. */
typedef struct vv_ray {
    vv_vec3 origin;
    vv_vec3 dir;
} vv_ray;

/** Axis-aligned box [min, max]. */
typedef struct vv_box {
    vv_vec3 min;
    vv_vec3 max;
} vv_box;

/** Plane n·x + d = 0, n unit. */
typedef struct vv_plane {
    vv_vec3 n;
    double d;
} vv_plane;

/* Component arithmetic on vectors: a + b, a - b, s a, a ∘ b, a · b, a × b, |a|. */
vv_vec3 vv_vec3_make(double x, double y, double z);
vv_vec3 vv_vec3_add(vv_vec3 a, vv_vec3 b);
vv_vec3 vv_vec3_sub(vv_vec3 a, vv_vec3 b);
vv_vec3 vv_vec3_scale(vv_vec3 a, double s);
vv_vec3 vv_vec3_mul(vv_vec3 a, vv_vec3 b); /**< component-wise */
double vv_vec3_dot(vv_vec3 a, vv_vec3 b);
vv_vec3 vv_vec3_cross(vv_vec3 a, vv_vec3 b);
double vv_vec3_length(vv_vec3 a);
/** a / |a|; the zero vector is returned unchanged. */
vv_vec3 vv_vec3_normalize(vv_vec3 a);
/** a + t (b - a). */
vv_vec3 vv_vec3_lerp(vv_vec3 a, vv_vec3 b, double t);

/* Identity, product a b (b applied first), transpose. */
vv_mat4 vv_mat4_identity(void);
vv_mat4 vv_mat4_mul(vv_mat4 a, vv_mat4 b);
vv_mat4 vv_mat4_transpose(vv_mat4 a);
/** General inverse; *ok (may be NULL) is 0 for a singular matrix (returns identity). */
vv_mat4 vv_mat4_inverse(vv_mat4 a, int *ok);
/** M (x, y, z, 1), with the perspective divide when the w row is not (0,0,0,1). */
vv_vec3 vv_mat4_mul_point(vv_mat4 m, vv_vec3 p);
/** Upper 3x3 times v (no translation). */
vv_vec3 vv_mat4_mul_dir(vv_mat4 m, vv_vec3 v);
/* Translation by t; scaling by s along the axes. */
vv_mat4 vv_mat4_translate(vv_vec3 t);
vv_mat4 vv_mat4_scale(vv_vec3 s);
/** Rotation by @p angle radians about @p axis (need not be unit), right-handed. */
vv_mat4 vv_mat4_rotate(vv_vec3 axis, double angle);
/** World-to-camera matrix: eye at the origin looking down -z, up is +y. */
vv_mat4 vv_mat4_look_at(vv_vec3 eye, vv_vec3 at, vv_vec3 up);
/** OpenGL-style perspective projection; fovy in radians, clip z to [-1, 1]. */
vv_mat4 vv_mat4_perspective(double fovy, double aspect, double znear, double zfar);
/** OpenGL-style orthographic projection onto clip space [-1, 1]^3. */
vv_mat4 vv_mat4_orthographic(double left, double right, double bottom, double top, double znear,
                             double zfar);

/** The identity rotation (1, 0, 0, 0). */
vv_quat vv_quat_identity(void);
/** Rotation by @p angle radians about @p axis (need not be unit). */
vv_quat vv_quat_from_axis_angle(vv_vec3 axis, double angle);
/** a * b: rotation b then a. */
vv_quat vv_quat_mul(vv_quat a, vv_quat b);
/** q / |q| (identity for the zero quaternion); conjugate (inverse of a unit q). */
vv_quat vv_quat_normalize(vv_quat q);
vv_quat vv_quat_conjugate(vv_quat q);
/** Spherical linear interpolation along the shorter arc, t in [0, 1]. */
vv_quat vv_quat_slerp(vv_quat a, vv_quat b, double t);
/** v rotated by q (q v q*); the same rotation as a matrix. */
vv_vec3 vv_quat_rotate(vv_quat q, vv_vec3 v);
vv_mat4 vv_quat_to_mat4(vv_quat q);

/** Point on the ray at parameter t. */
vv_vec3 vv_ray_at(vv_ray r, double t);

/**
 * Slab test. On a hit returns 1 and the entry and exit parameters (*t0 <= *t1,
 * *t0 may be negative when the origin is inside); 0 on a miss.
 */
int vv_box_intersect_ray(vv_box b, vv_ray r, double *t0, double *t1);
vv_box vv_box_transform(vv_box b, vv_mat4 m); /**< bounding box of the 8 transformed corners */

/** Plane through @p point with normal @p normal (normalised here). */
vv_plane vv_plane_from_point_normal(vv_vec3 point, vv_vec3 normal);
/** Signed distance n·p + d (positive on the side the normal points to). */
double vv_plane_distance(vv_plane pl, vv_vec3 p);
/**
 * Clips the ray interval [*t0, *t1] to the half-space n·x + d >= 0. Returns 0
 * when nothing of the interval remains.
 */
int vv_plane_clip_ray(vv_plane pl, vv_ray r, double *t0, double *t1);

/** Degrees to radians and back (files and the CLI use degrees). */
double vv_deg_to_rad(double deg);
double vv_rad_to_deg(double rad);

#ifdef __cplusplus
}
#endif
#endif
