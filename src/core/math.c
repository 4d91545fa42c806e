/* Vectors, matrices, quaternions, rays, boxes, planes (see volvis/math.h). */
#include <math.h>

#include "core/geom.h"
#include "volvis/math.h"

vv_vec3
vv_vec3_make(double x, double y, double z) {
    vv_vec3 v = {x, y, z};
    return v;
}

vv_vec3
vv_vec3_add(vv_vec3 a, vv_vec3 b) {
    return vv_vec3_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

vv_vec3
vv_vec3_sub(vv_vec3 a, vv_vec3 b) {
    return vv_vec3_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

vv_vec3
vv_vec3_scale(vv_vec3 a, double s) {
    return vv_vec3_make(a.x * s, a.y * s, a.z * s);
}

vv_vec3
vv_vec3_mul(vv_vec3 a, vv_vec3 b) {
    return vv_vec3_make(a.x * b.x, a.y * b.y, a.z * b.z);
}

double
vv_vec3_dot(vv_vec3 a, vv_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

vv_vec3
vv_vec3_cross(vv_vec3 a, vv_vec3 b) {
    return vv_vec3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

double
vv_vec3_length(vv_vec3 a) {
    return sqrt(vv_vec3_dot(a, a));
}

vv_vec3
vv_vec3_normalize(vv_vec3 a) {
    double l = vv_vec3_length(a);
    return l > 0 ? vv_vec3_scale(a, 1.0 / l) : a;
}

vv_vec3
vv_vec3_lerp(vv_vec3 a, vv_vec3 b, double t) {
    return vv_vec3_add(a, vv_vec3_scale(vv_vec3_sub(b, a), t));
}

vv_mat4
vv_mat4_identity(void) {
    vv_mat4 r = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    return r;
}

vv_mat4
vv_mat4_mul(vv_mat4 a, vv_mat4 b) {
    vv_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0;
            for (int k = 0; k < 4; k++)
                s += a.m[i][k] * b.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

vv_mat4
vv_mat4_transpose(vv_mat4 a) {
    vv_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            r.m[i][j] = a.m[j][i];
    return r;
}

vv_mat4
vv_mat4_inverse(vv_mat4 a, int *ok) {
    /* Gauss-Jordan elimination with partial pivoting. */
    double m[4][8];
    /* a pivot below this (relative to the largest entry) means singular:
     * rounding rarely leaves an exact zero */
    double scale = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            scale = fabs(a.m[i][j]) > scale ? fabs(a.m[i][j]) : scale;
    const double tiny = 1e-12 * scale;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            m[i][j] = a.m[i][j];
            m[i][j + 4] = i == j;
        }
    for (int c = 0; c < 4; c++) {
        int p = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(m[r][c]) > fabs(m[p][c]))
                p = r;
        if (!(fabs(m[p][c]) > tiny)) {
            if (ok)
                *ok = 0;
            return vv_mat4_identity();
        }
        if (p != c)
            for (int j = 0; j < 8; j++) {
                double t = m[c][j];
                m[c][j] = m[p][j];
                m[p][j] = t;
            }
        double inv = 1.0 / m[c][c];
        for (int j = 0; j < 8; j++)
            m[c][j] *= inv;
        for (int r = 0; r < 4; r++) {
            if (r == c)
                continue;
            double f = m[r][c];
            if (f != 0)
                for (int j = 0; j < 8; j++)
                    m[r][j] -= f * m[c][j];
        }
    }
    vv_mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            r.m[i][j] = m[i][j + 4];
    if (ok)
        *ok = 1;
    return r;
}

vv_vec3
vv_mat4_mul_point(vv_mat4 m, vv_vec3 p) {
    double x = m.m[0][0] * p.x + m.m[0][1] * p.y + m.m[0][2] * p.z + m.m[0][3];
    double y = m.m[1][0] * p.x + m.m[1][1] * p.y + m.m[1][2] * p.z + m.m[1][3];
    double z = m.m[2][0] * p.x + m.m[2][1] * p.y + m.m[2][2] * p.z + m.m[2][3];
    double w = m.m[3][0] * p.x + m.m[3][1] * p.y + m.m[3][2] * p.z + m.m[3][3];
    if (w != 1.0 && w != 0.0)
        return vv_vec3_make(x / w, y / w, z / w);
    return vv_vec3_make(x, y, z);
}

vv_vec3
vv_mat4_mul_dir(vv_mat4 m, vv_vec3 v) {
    return vv_vec3_make(m.m[0][0] * v.x + m.m[0][1] * v.y + m.m[0][2] * v.z,
                        m.m[1][0] * v.x + m.m[1][1] * v.y + m.m[1][2] * v.z,
                        m.m[2][0] * v.x + m.m[2][1] * v.y + m.m[2][2] * v.z);
}

vv_mat4
vv_mat4_translate(vv_vec3 t) {
    vv_mat4 r = vv_mat4_identity();
    r.m[0][3] = t.x;
    r.m[1][3] = t.y;
    r.m[2][3] = t.z;
    return r;
}

vv_mat4
vv_mat4_scale(vv_vec3 s) {
    vv_mat4 r = vv_mat4_identity();
    r.m[0][0] = s.x;
    r.m[1][1] = s.y;
    r.m[2][2] = s.z;
    return r;
}

vv_mat4
vv_mat4_rotate(vv_vec3 axis, double angle) {
    return vv_quat_to_mat4(vv_quat_from_axis_angle(axis, angle));
}

vv_mat4
vv_mat4_look_at(vv_vec3 eye, vv_vec3 at, vv_vec3 up) {
    vv_vec3 f = vv_vec3_normalize(vv_vec3_sub(at, eye));
    vv_vec3 s = vv_vec3_normalize(vv_vec3_cross(f, up));
    vv_vec3 u = vv_vec3_cross(s, f);
    vv_mat4 r = vv_mat4_identity();
    r.m[0][0] = s.x;
    r.m[0][1] = s.y;
    r.m[0][2] = s.z;
    r.m[1][0] = u.x;
    r.m[1][1] = u.y;
    r.m[1][2] = u.z;
    r.m[2][0] = -f.x;
    r.m[2][1] = -f.y;
    r.m[2][2] = -f.z;
    r.m[0][3] = -vv_vec3_dot(s, eye);
    r.m[1][3] = -vv_vec3_dot(u, eye);
    r.m[2][3] = vv_vec3_dot(f, eye);
    return r;
}

vv_mat4
vv_mat4_perspective(double fovy, double aspect, double znear, double zfar) {
    double f = 1.0 / tan(fovy / 2.0);
    vv_mat4 r = {{{0}}};
    r.m[0][0] = f / aspect;
    r.m[1][1] = f;
    r.m[2][2] = (zfar + znear) / (znear - zfar);
    r.m[2][3] = 2.0 * zfar * znear / (znear - zfar);
    r.m[3][2] = -1.0;
    return r;
}

vv_mat4
vv_mat4_orthographic(double left, double right, double bottom, double top, double znear,
                     double zfar) {
    vv_mat4 r = vv_mat4_identity();
    r.m[0][0] = 2.0 / (right - left);
    r.m[1][1] = 2.0 / (top - bottom);
    r.m[2][2] = -2.0 / (zfar - znear);
    r.m[0][3] = -(right + left) / (right - left);
    r.m[1][3] = -(top + bottom) / (top - bottom);
    r.m[2][3] = -(zfar + znear) / (zfar - znear);
    return r;
}

vv_quat
vv_quat_identity(void) {
    vv_quat q = {1, 0, 0, 0};
    return q;
}

vv_quat
vv_quat_from_axis_angle(vv_vec3 axis, double angle) {
    vv_vec3 a = vv_vec3_normalize(axis);
    double s = sin(angle / 2.0);
    vv_quat q = {cos(angle / 2.0), a.x * s, a.y * s, a.z * s};
    return q;
}

vv_quat
vv_quat_mul(vv_quat a, vv_quat b) {
    vv_quat r = {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
                 a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                 a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                 a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
    return r;
}

vv_quat
vv_quat_normalize(vv_quat q) {
    double l = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    if (l <= 0)
        return vv_quat_identity();
    vv_quat r = {q.w / l, q.x / l, q.y / l, q.z / l};
    return r;
}

vv_quat
vv_quat_conjugate(vv_quat q) {
    vv_quat r = {q.w, -q.x, -q.y, -q.z};
    return r;
}

vv_quat
vv_quat_slerp(vv_quat a, vv_quat b, double t) {
    double d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
    if (d < 0) {
        d = -d;
        b.w = -b.w;
        b.x = -b.x;
        b.y = -b.y;
        b.z = -b.z;
    }
    double wa, wb;
    if (d > 0.9995) {
        wa = 1 - t;
        wb = t;
    } else {
        double th = acos(d), s = sin(th);
        wa = sin((1 - t) * th) / s;
        wb = sin(t * th) / s;
    }
    vv_quat r = {wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y,
                 wa * a.z + wb * b.z};
    return vv_quat_normalize(r);
}

vv_vec3
vv_quat_rotate(vv_quat q, vv_vec3 v) {
    vv_quat p = {0, v.x, v.y, v.z};
    vv_quat r = vv_quat_mul(vv_quat_mul(q, p), vv_quat_conjugate(q));
    return vv_vec3_make(r.x, r.y, r.z);
}

vv_mat4
vv_quat_to_mat4(vv_quat q) {
    q = vv_quat_normalize(q);
    double w = q.w, x = q.x, y = q.y, z = q.z;
    vv_mat4 r = vv_mat4_identity();
    r.m[0][0] = 1 - 2 * (y * y + z * z);
    r.m[0][1] = 2 * (x * y - w * z);
    r.m[0][2] = 2 * (x * z + w * y);
    r.m[1][0] = 2 * (x * y + w * z);
    r.m[1][1] = 1 - 2 * (x * x + z * z);
    r.m[1][2] = 2 * (y * z - w * x);
    r.m[2][0] = 2 * (x * z - w * y);
    r.m[2][1] = 2 * (y * z + w * x);
    r.m[2][2] = 1 - 2 * (x * x + y * y);
    return r;
}

vv_vec3
vv_ray_at(vv_ray r, double t) {
    return vv_vec3_add(r.origin, vv_vec3_scale(r.dir, t));
}

int
vv_box_intersect_ray(vv_box b, vv_ray r, double *t0, double *t1) {
    const double o[3] = {r.origin.x, r.origin.y, r.origin.z};
    const double d[3] = {r.dir.x, r.dir.y, r.dir.z};
    const double mn[3] = {b.min.x, b.min.y, b.min.z};
    const double mx[3] = {b.max.x, b.max.y, b.max.z};
    double lo = -INFINITY, hi = INFINITY;
    if (!vv_slab(mn, mx, o, d, &lo, &hi))
        return 0;
    *t0 = lo;
    *t1 = hi;
    return 1;
}

vv_box
vv_box_transform(vv_box b, vv_mat4 m) {
    vv_box r = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (int c = 0; c < 8; c++) {
        vv_vec3 p = vv_vec3_make(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y,
                                 c & 4 ? b.max.z : b.min.z);
        p = vv_mat4_mul_point(m, p);
        r.min.x = fmin(r.min.x, p.x);
        r.min.y = fmin(r.min.y, p.y);
        r.min.z = fmin(r.min.z, p.z);
        r.max.x = fmax(r.max.x, p.x);
        r.max.y = fmax(r.max.y, p.y);
        r.max.z = fmax(r.max.z, p.z);
    }
    return r;
}

vv_plane
vv_plane_from_point_normal(vv_vec3 point, vv_vec3 normal) {
    vv_plane p;
    p.n = vv_vec3_normalize(normal);
    p.d = -vv_vec3_dot(p.n, point);
    return p;
}

double
vv_plane_distance(vv_plane pl, vv_vec3 p) {
    return vv_vec3_dot(pl.n, p) + pl.d;
}

int
vv_plane_clip_ray(vv_plane pl, vv_ray r, double *t0, double *t1) {
    double dn = vv_vec3_dot(pl.n, r.dir);
    double s0 = vv_plane_distance(pl, r.origin);
    if (dn == 0)
        return s0 >= 0 && *t0 <= *t1;
    double t = -s0 / dn;
    if (dn > 0) {
        if (t > *t0)
            *t0 = t;
    } else {
        if (t < *t1)
            *t1 = t;
    }
    return *t0 <= *t1;
}

double
vv_deg_to_rad(double deg) {
    return deg * (VV_PI / 180.0);
}

double
vv_rad_to_deg(double rad) {
    return rad * (180.0 / VV_PI);
}
