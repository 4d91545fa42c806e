/* Math: vectors, matrices, projections, quaternions, rays, boxes, planes. */
#include "testutil.h"

#include <math.h>
#include <stdint.h>

#define EPS 1e-12

static void
assert_vec_near(vv_vec3 got, vv_vec3 want, double tol) {
    if (!(fabs(got.x - want.x) <= tol && fabs(got.y - want.y) <= tol &&
          fabs(got.z - want.z) <= tol))
        fail_msg("got (%.17g, %.17g, %.17g), want (%.17g, %.17g, %.17g) (tolerance %g)", got.x,
                 got.y, got.z, want.x, want.y, want.z, tol);
}

static void
assert_mat_near(vv_mat4 got, vv_mat4 want, double tol) {
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (!(fabs(got.m[i][j] - want.m[i][j]) <= tol))
                fail_msg("m[%d][%d]: got %.17g, want %.17g (tolerance %g)", i, j, got.m[i][j],
                         want.m[i][j], tol);
}

/* Deterministic uniform numbers in [lo, hi) (splitmix64). */
static double
rnd(uint64_t *s, double lo, double hi) {
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) / 9007199254740992.0;
}

static vv_vec3
rnd_vec(uint64_t *s, double lo, double hi) {
    double x = rnd(s, lo, hi), y = rnd(s, lo, hi), z = rnd(s, lo, hi);
    return vv_vec3_make(x, y, z);
}

/* Rodrigues' rotation formula, independent of the quaternion code. */
static vv_vec3
rodrigues(vv_vec3 axis, double angle, vv_vec3 v) {
    vv_vec3 k = vv_vec3_normalize(axis);
    double c = cos(angle), s = sin(angle);
    return vv_vec3_add(vv_vec3_add(vv_vec3_scale(v, c), vv_vec3_scale(vv_vec3_cross(k, v), s)),
                       vv_vec3_scale(k, vv_vec3_dot(k, v) * (1 - c)));
}

static void
test_vec3(void **state) {
    (void)state;
    vv_vec3 a = vv_vec3_make(1, 2, 3), b = vv_vec3_make(-4, 5, 0.5);
    assert_vec_near(vv_vec3_add(a, b), vv_vec3_make(-3, 7, 3.5), 0);
    assert_vec_near(vv_vec3_sub(a, b), vv_vec3_make(5, -3, 2.5), 0);
    assert_vec_near(vv_vec3_scale(a, -2), vv_vec3_make(-2, -4, -6), 0);
    assert_vec_near(vv_vec3_mul(a, b), vv_vec3_make(-4, 10, 1.5), 0);
    assert_near(vv_vec3_dot(a, b), -4 + 10 + 1.5, 0);
    /* right-handed: x × y = z, y × z = x, z × x = y */
    assert_vec_near(vv_vec3_cross(vv_vec3_make(1, 0, 0), vv_vec3_make(0, 1, 0)),
                    vv_vec3_make(0, 0, 1), 0);
    assert_vec_near(vv_vec3_cross(vv_vec3_make(0, 1, 0), vv_vec3_make(0, 0, 1)),
                    vv_vec3_make(1, 0, 0), 0);
    assert_vec_near(vv_vec3_cross(vv_vec3_make(0, 0, 1), vv_vec3_make(1, 0, 0)),
                    vv_vec3_make(0, 1, 0), 0);
    vv_vec3 c = vv_vec3_cross(a, b);
    assert_near(vv_vec3_dot(c, a), 0, EPS);
    assert_near(vv_vec3_dot(c, b), 0, EPS);
    assert_vec_near(c, vv_vec3_make(2 * 0.5 - 3 * 5, 3 * -4 - 1 * 0.5, 1 * 5 - 2 * -4), 0);
    assert_near(vv_vec3_length(vv_vec3_make(3, 4, 12)), 13, 0);
    vv_vec3 n = vv_vec3_normalize(vv_vec3_make(0, -3, 4));
    assert_vec_near(n, vv_vec3_make(0, -0.6, 0.8), EPS);
    assert_near(vv_vec3_length(vv_vec3_normalize(b)), 1, EPS);
    /* the zero vector is returned unchanged, not NaN */
    vv_vec3 z = vv_vec3_normalize(vv_vec3_make(0, 0, 0));
    assert_true(z.x == 0 && z.y == 0 && z.z == 0);
    assert_vec_near(vv_vec3_lerp(a, b, 0), a, 0);
    assert_vec_near(vv_vec3_lerp(a, b, 1), b, EPS);
    assert_vec_near(vv_vec3_lerp(a, b, 0.25), vv_vec3_make(1 - 1.25, 2 + 0.75, 3 - 0.625), EPS);
    assert_near(vv_deg_to_rad(180), VV_PI, EPS);
    assert_near(vv_deg_to_rad(-90), -VV_PI / 2, EPS);
    assert_near(vv_rad_to_deg(VV_PI / 4), 45, EPS);
    assert_near(vv_rad_to_deg(vv_deg_to_rad(37.5)), 37.5, EPS);
}

static void
test_mat4_mul_identity_transpose(void **state) {
    (void)state;
    vv_mat4 a, b;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            a.m[i][j] = i * 4 + j + 1;
            b.m[i][j] = (i == j) ? 2 : (i - j);
        }
    assert_mat_near(vv_mat4_mul(a, vv_mat4_identity()), a, 0);
    assert_mat_near(vv_mat4_mul(vv_mat4_identity(), a), a, 0);
    /* (A B)[i][j] = sum_k A[i][k] B[k][j], checked on one entry by hand:
     * row 1 of A is 5 6 7 8, column 2 of B is (-2, -1, 2, 1) */
    vv_mat4 ab = vv_mat4_mul(a, b);
    assert_near(ab.m[1][2], 5 * -2 + 6 * -1 + 7 * 2 + 8 * 1, 0);
    /* (AB)^T = B^T A^T */
    assert_mat_near(vv_mat4_transpose(ab), vv_mat4_mul(vv_mat4_transpose(b), vv_mat4_transpose(a)),
                    1e-9);
    assert_near(vv_mat4_transpose(a).m[0][3], a.m[3][0], 0);
}

static void
test_mat4_inverse_random(void **state) {
    (void)state;
    uint64_t seed = 12345;
    for (int trial = 0; trial < 200; trial++) {
        vv_mat4 a;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                a.m[i][j] = rnd(&seed, -1, 1) + (i == j ? 4.0 : 0.0); /* diagonally dominant */
        if (trial % 2) { /* also full affine transforms with a perspective-free w row */
            a = vv_mat4_mul(vv_mat4_translate(rnd_vec(&seed, -10, 10)),
                            vv_mat4_mul(vv_mat4_rotate(rnd_vec(&seed, -1, 1), rnd(&seed, -3, 3)),
                                        vv_mat4_scale(rnd_vec(&seed, 0.1, 5))));
        }
        int ok = -1;
        vv_mat4 inv = vv_mat4_inverse(a, &ok);
        assert_int_equal(ok, 1);
        assert_mat_near(vv_mat4_mul(a, inv), vv_mat4_identity(), 1e-12);
        assert_mat_near(vv_mat4_mul(inv, a), vv_mat4_identity(), 1e-12);
        /* points round trip */
        vv_vec3 p = rnd_vec(&seed, -5, 5);
        assert_vec_near(vv_mat4_mul_point(inv, vv_mat4_mul_point(a, p)), p, 1e-11);
    }
    /* NULL ok is allowed; scale is inverted exactly */
    vv_mat4 s = vv_mat4_inverse(vv_mat4_scale(vv_vec3_make(2, 4, 0.5)), NULL);
    assert_mat_near(s, vv_mat4_scale(vv_vec3_make(0.5, 0.25, 2)), 0);
    /* a well-conditioned but tiny matrix is not "singular" */
    int ok = 0;
    vv_mat4 t = vv_mat4_inverse(vv_mat4_scale(vv_vec3_make(1e-6, 1e-6, 1e-6)), &ok);
    assert_int_equal(ok, 1);
    assert_near(t.m[0][0], 1e6, 1e-6);
}

static void
test_mat4_inverse_singular(void **state) {
    (void)state;
    vv_mat4 zero = {{{0}}};
    int ok = -1;
    vv_mat4 r = vv_mat4_inverse(zero, &ok);
    assert_int_equal(ok, 0);
    assert_mat_near(r, vv_mat4_identity(), 0); /* documented: identity */

    /* two equal rows */
    vv_mat4 a = vv_mat4_identity();
    a.m[1][0] = 1;
    a.m[1][1] = 0;
    a.m[0][0] = 1;
    ok = -1;
    vv_mat4_inverse(a, &ok);
    assert_int_equal(ok, 0);

    /* projection onto a plane: scale with a zero axis */
    ok = -1;
    vv_mat4_inverse(vv_mat4_scale(vv_vec3_make(1, 0, 1)), &ok);
    assert_int_equal(ok, 0);
}

static void
check_singular(vv_mat4 a, const char *what) {
    int ok = -1;
    vv_mat4 inv = vv_mat4_inverse(a, &ok);
    if (ok) {
        double mx = 0;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                mx = fmax(mx, fabs(inv.m[i][j]));
        fail_msg("singular %s reported invertible, max |inverse entry| = %g", what, mx);
    }
}

/* The classic singular matrix whose elimination does not give an exact zero
 * pivot in floating point: it must still be reported as singular rather than
 * "inverted" into entries of size 1e16. */
static void
test_mat4_inverse_numerically_singular(void **state) {
    (void)state;
    vv_mat4 a = {{{1, 2, 3, 0}, {4, 5, 6, 0}, {7, 8, 9, 0}, {0, 0, 0, 1}}};
    check_singular(a, "[[1,2,3,0],[4,5,6,0],[7,8,9,0],[0,0,0,1]]");
    /* rank 3: third row = first + second, in small integers */
    vv_mat4 b = {{{1, 2, 3, 4}, {2, 1, 0, 1}, {3, 3, 3, 5}, {0, 0, 1, 1}}};
    check_singular(b, "[[1,2,3,4],[2,1,0,1],[3,3,3,5],[0,0,1,1]]");
    vv_mat4 c = {{{0.1, 0.2, 0.3, 0}, {0.4, 0.5, 0.6, 0}, {0.7, 0.8, 0.9, 0}, {0, 0, 0, 1}}};
    check_singular(c, "[[.1,.2,.3,0],[.4,.5,.6,0],[.7,.8,.9,0],[0,0,0,1]]");
}

static void
test_mat4_convention(void **state) {
    (void)state;
    vv_mat4 t = vv_mat4_translate(vv_vec3_make(1, 2, 3));
    /* row-major, translation in the last column */
    assert_true(t.m[0][3] == 1 && t.m[1][3] == 2 && t.m[2][3] == 3);
    assert_true(t.m[3][0] == 0 && t.m[3][1] == 0 && t.m[3][2] == 0 && t.m[3][3] == 1);
    assert_vec_near(vv_mat4_mul_point(t, vv_vec3_make(0, 0, 0)), vv_vec3_make(1, 2, 3), 0);
    assert_vec_near(vv_mat4_mul_point(t, vv_vec3_make(10, 20, 30)), vv_vec3_make(11, 22, 33), 0);
    /* directions ignore the translation */
    assert_vec_near(vv_mat4_mul_dir(t, vv_vec3_make(10, 20, 30)), vv_vec3_make(10, 20, 30), 0);
    /* A * B applies B first: translate after scale */
    vv_mat4 s = vv_mat4_scale(vv_vec3_make(2, 3, 4));
    vv_vec3 p = vv_vec3_make(1, 1, 1);
    assert_vec_near(vv_mat4_mul_point(vv_mat4_mul(t, s), p), vv_vec3_make(3, 5, 7), 0);
    assert_vec_near(vv_mat4_mul_point(vv_mat4_mul(s, t), p), vv_vec3_make(4, 9, 16), 0);
    /* perspective divide when the w row is not (0, 0, 0, 1) */
    vv_mat4 w = vv_mat4_identity();
    w.m[3][3] = 2;
    assert_vec_near(vv_mat4_mul_point(w, vv_vec3_make(2, 4, 6)), vv_vec3_make(1, 2, 3), 0);
}

static void
test_mat4_rotate(void **state) {
    (void)state;
    vv_vec3 x = vv_vec3_make(1, 0, 0), y = vv_vec3_make(0, 1, 0), z = vv_vec3_make(0, 0, 1);
    double q = VV_PI / 2;
    /* right-handed: about z, x -> y, y -> -x; about x, y -> z; about y, z -> x */
    vv_mat4 rz = vv_mat4_rotate(z, q);
    assert_vec_near(vv_mat4_mul_point(rz, x), y, EPS);
    assert_vec_near(vv_mat4_mul_point(rz, y), vv_vec3_scale(x, -1), EPS);
    assert_vec_near(vv_mat4_mul_point(rz, z), z, EPS);
    assert_vec_near(vv_mat4_mul_point(vv_mat4_rotate(x, q), y), z, EPS);
    assert_vec_near(vv_mat4_mul_point(vv_mat4_rotate(y, q), z), x, EPS);
    /* the axis need not be unit */
    assert_mat_near(vv_mat4_rotate(vv_vec3_make(0, 0, 7), 0.3), vv_mat4_rotate(z, 0.3), EPS);
    /* against Rodrigues' formula, and orthonormal with det +1 */
    uint64_t seed = 99;
    for (int trial = 0; trial < 100; trial++) {
        vv_vec3 axis = rnd_vec(&seed, -1, 1);
        double angle = rnd(&seed, -7, 7);
        vv_mat4 r = vv_mat4_rotate(axis, angle);
        vv_vec3 v = rnd_vec(&seed, -3, 3);
        assert_vec_near(vv_mat4_mul_point(r, v), rodrigues(axis, angle, v), 1e-12);
        assert_mat_near(vv_mat4_mul(r, vv_mat4_transpose(r)), vv_mat4_identity(), 1e-12);
        vv_vec3 c0 = vv_vec3_make(r.m[0][0], r.m[1][0], r.m[2][0]);
        vv_vec3 c1 = vv_vec3_make(r.m[0][1], r.m[1][1], r.m[2][1]);
        vv_vec3 c2 = vv_vec3_make(r.m[0][2], r.m[1][2], r.m[2][2]);
        assert_near(vv_vec3_dot(vv_vec3_cross(c0, c1), c2), 1, 1e-12);
        assert_near(r.m[0][3], 0, 0);
        assert_near(r.m[3][3], 1, 0);
    }
}

static void
test_mat4_look_at(void **state) {
    (void)state;
    vv_vec3 eye = vv_vec3_make(3, -2, 5), at = vv_vec3_make(-1, 4, 2), up = vv_vec3_make(0, 0, 1);
    vv_mat4 v = vv_mat4_look_at(eye, at, up);
    assert_vec_near(vv_mat4_mul_point(v, eye), vv_vec3_make(0, 0, 0), 1e-12);
    double dist = vv_vec3_length(vv_vec3_sub(at, eye));
    assert_vec_near(vv_mat4_mul_point(v, at), vv_vec3_make(0, 0, -dist), 1e-12);
    /* up maps into the upper half of the y-z plane (x = 0, y > 0) */
    vv_vec3 u = vv_mat4_mul_dir(v, up);
    assert_near(u.x, 0, 1e-12);
    assert_true(u.y > 0);
    /* a rigid transform: rotation part orthonormal with det +1 */
    vv_mat4 r = v;
    r.m[0][3] = r.m[1][3] = r.m[2][3] = 0;
    assert_mat_near(vv_mat4_mul(r, vv_mat4_transpose(r)), vv_mat4_identity(), 1e-12);
    vv_vec3 c0 = vv_vec3_make(r.m[0][0], r.m[1][0], r.m[2][0]);
    vv_vec3 c1 = vv_vec3_make(r.m[0][1], r.m[1][1], r.m[2][1]);
    vv_vec3 c2 = vv_vec3_make(r.m[0][2], r.m[1][2], r.m[2][2]);
    assert_near(vv_vec3_dot(vv_vec3_cross(c0, c1), c2), 1, 1e-12);
    /* the standard camera: eye on +z looking at the origin, +y up, is a translation */
    vv_mat4 std =
        vv_mat4_look_at(vv_vec3_make(0, 0, 5), vv_vec3_make(0, 0, 0), vv_vec3_make(0, 1, 0));
    assert_mat_near(std, vv_mat4_translate(vv_vec3_make(0, 0, -5)), 1e-15);
    vv_mat4 side =
        vv_mat4_look_at(vv_vec3_make(5, 0, 0), vv_vec3_make(0, 0, 0), vv_vec3_make(0, 1, 0));
    /* looking down -x with +y up, the right-hand side is -z */
    assert_vec_near(vv_mat4_mul_dir(side, vv_vec3_make(0, 0, -1)), vv_vec3_make(1, 0, 0), 1e-12);
}

static void
test_mat4_perspective(void **state) {
    (void)state;
    double fovy = vv_deg_to_rad(60), aspect = 1.5, n = 0.5, f = 100;
    vv_mat4 p = vv_mat4_perspective(fovy, aspect, n, f);
    double th = tan(fovy / 2);
    for (int c = 0; c < 8; c++) {
        double z = (c & 4) ? f : n;
        double sx = (c & 1) ? 1 : -1, sy = (c & 2) ? 1 : -1;
        vv_vec3 corner = vv_vec3_make(sx * z * th * aspect, sy * z * th, -z);
        vv_vec3 clip = vv_mat4_mul_point(p, corner);
        assert_vec_near(clip, vv_vec3_make(sx, sy, (c & 4) ? 1 : -1), 1e-9);
    }
    /* depth increases monotonically from near to far */
    double prev = -2;
    for (double z = n; z <= f; z *= 1.7) {
        double d = vv_mat4_mul_point(p, vv_vec3_make(0, 0, -z)).z;
        assert_true(d > prev);
        prev = d;
    }
}

static void
test_mat4_orthographic(void **state) {
    (void)state;
    double l = -3, r = 5, b = -1, t = 2, n = 0.25, f = 40;
    vv_mat4 o = vv_mat4_orthographic(l, r, b, t, n, f);
    for (int c = 0; c < 8; c++) {
        vv_vec3 corner = vv_vec3_make((c & 1) ? r : l, (c & 2) ? t : b, (c & 4) ? -f : -n);
        vv_vec3 clip = vv_mat4_mul_point(o, corner);
        assert_vec_near(clip, vv_vec3_make((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1),
                        1e-12);
    }
    assert_vec_near(vv_mat4_mul_point(o, vv_vec3_make(1, 0.5, -(n + f) / 2)), vv_vec3_make(0, 0, 0),
                    1e-12);
}

static void
test_quat(void **state) {
    (void)state;
    uint64_t seed = 7;
    for (int trial = 0; trial < 100; trial++) {
        vv_vec3 axis = rnd_vec(&seed, -1, 1);
        double angle = rnd(&seed, -7, 7);
        vv_quat q = vv_quat_from_axis_angle(axis, angle);
        assert_near(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z, 1, 1e-12);
        vv_vec3 v = rnd_vec(&seed, -3, 3);
        /* quaternion sandwich, matrix and Rodrigues all agree */
        vv_vec3 want = rodrigues(axis, angle, v);
        assert_vec_near(vv_quat_rotate(q, v), want, 1e-12);
        assert_vec_near(vv_mat4_mul_dir(vv_quat_to_mat4(q), v), want, 1e-12);
        assert_mat_near(vv_quat_to_mat4(q), vv_mat4_rotate(axis, angle), 1e-12);
        /* to_mat4 normalises: a scaled quaternion is the same rotation */
        vv_quat q3 = {3 * q.w, 3 * q.x, 3 * q.y, 3 * q.z};
        assert_mat_near(vv_quat_to_mat4(q3), vv_quat_to_mat4(q), 1e-12);
        /* conjugate is the inverse */
        assert_vec_near(vv_quat_rotate(vv_quat_conjugate(q), vv_quat_rotate(q, v)), v, 1e-12);
        /* composition: a * b applies b first */
        vv_quat p = vv_quat_from_axis_angle(rnd_vec(&seed, -1, 1), rnd(&seed, -3, 3));
        vv_quat pq = vv_quat_mul(p, q);
        assert_vec_near(vv_quat_rotate(pq, v), vv_quat_rotate(p, vv_quat_rotate(q, v)), 1e-12);
        assert_mat_near(vv_quat_to_mat4(pq), vv_mat4_mul(vv_quat_to_mat4(p), vv_quat_to_mat4(q)),
                        1e-12);
    }
    /* non-commutative: z then x differs from x then z */
    vv_quat a = vv_quat_from_axis_angle(vv_vec3_make(0, 0, 1), VV_PI / 2);
    vv_quat b = vv_quat_from_axis_angle(vv_vec3_make(1, 0, 0), VV_PI / 2);
    vv_vec3 v = vv_vec3_make(1, 0, 0);
    assert_vec_near(vv_quat_rotate(vv_quat_mul(b, a), v), vv_vec3_make(0, 0, 1), 1e-12);
    assert_vec_near(vv_quat_rotate(vv_quat_mul(a, b), v), vv_vec3_make(0, 1, 0), 1e-12);
    vv_quat id = vv_quat_identity();
    assert_true(id.w == 1 && id.x == 0 && id.y == 0 && id.z == 0);
    vv_quat zq = {0, 0, 0, 0};
    vv_quat zn = vv_quat_normalize(zq);
    assert_true(zn.w == 1 && zn.x == 0 && zn.y == 0 && zn.z == 0);
    vv_quat big = {0, 0, 0, 5};
    vv_quat bn = vv_quat_normalize(big);
    assert_near(bn.z, 1, 0);
}

/* Rotation angle of a unit quaternion, in [0, pi]. */
static double
quat_angle(vv_quat q) {
    return 2 * acos(fmin(1.0, fabs(q.w)));
}

/* Angle of the rotation that takes a to b. */
static double
quat_angle_between(vv_quat a, vv_quat b) {
    return quat_angle(vv_quat_mul(vv_quat_conjugate(a), b));
}

static void
test_quat_slerp(void **state) {
    (void)state;
    vv_vec3 z = vv_vec3_make(0, 0, 1);
    vv_quat id = vv_quat_identity();
    vv_quat b = vv_quat_from_axis_angle(z, vv_deg_to_rad(100));
    assert_near(quat_angle_between(vv_quat_slerp(id, b, 0), id), 0, 1e-7);
    assert_near(quat_angle_between(vv_quat_slerp(id, b, 1), b), 0, 1e-7);
    vv_quat mid = vv_quat_slerp(id, b, 0.5);
    assert_mat_near(vv_quat_to_mat4(mid), vv_mat4_rotate(z, vv_deg_to_rad(50)), 1e-12);
    vv_quat q3 = vv_quat_slerp(id, b, 0.3);
    assert_mat_near(vv_quat_to_mat4(q3), vv_mat4_rotate(z, vv_deg_to_rad(30)), 1e-12);
    /* -b is the same rotation: the result is the same rotation */
    vv_quat nb = {-b.w, -b.x, -b.y, -b.z};
    assert_mat_near(vv_quat_to_mat4(vv_quat_slerp(id, nb, 0.5)), vv_quat_to_mat4(mid), 1e-12);
    /* shorter arc: halfway to +300 degrees is -30 degrees, not +150 */
    vv_quat c = vv_quat_from_axis_angle(z, vv_deg_to_rad(300));
    assert_mat_near(vv_quat_to_mat4(vv_quat_slerp(id, c, 0.5)),
                    vv_mat4_rotate(z, vv_deg_to_rad(-30)), 1e-12);
    /* random pairs: the midpoint is half the angle from each end, unit length */
    uint64_t seed = 3;
    for (int trial = 0; trial < 100; trial++) {
        vv_quat qa = vv_quat_from_axis_angle(rnd_vec(&seed, -1, 1), rnd(&seed, -3, 3));
        vv_quat qb = vv_quat_from_axis_angle(rnd_vec(&seed, -1, 1), rnd(&seed, -3, 3));
        double full = quat_angle_between(qa, qb);
        vv_quat m = vv_quat_slerp(qa, qb, 0.5);
        assert_near(m.w * m.w + m.x * m.x + m.y * m.y + m.z * m.z, 1, 1e-12);
        assert_near(quat_angle_between(qa, m), full / 2, 1e-7);
        assert_near(quat_angle_between(m, qb), full / 2, 1e-7);
        vv_quat e1 = vv_quat_slerp(qa, qb, 1);
        assert_near(quat_angle_between(e1, qb), 0, 1e-7);
    }
    /* nearly equal quaternions (the linear branch) stay accurate */
    vv_quat s = vv_quat_from_axis_angle(z, 0.01);
    assert_mat_near(vv_quat_to_mat4(vv_quat_slerp(id, s, 0.5)), vv_mat4_rotate(z, 0.005), 1e-9);
}

static void
test_box_ray(void **state) {
    (void)state;
    vv_box b = {{0, 0, 0}, {1, 2, 3}};
    double t0 = 99, t1 = 99;
    vv_ray r = {{-1, 0.5, 0.5}, {1, 0, 0}};
    assert_int_equal(vv_box_intersect_ray(b, r, &t0, &t1), 1);
    assert_near(t0, 1, EPS);
    assert_near(t1, 2, EPS);
    /* a longer direction scales t */
    r.dir = vv_vec3_make(4, 0, 0);
    assert_int_equal(vv_box_intersect_ray(b, r, &t0, &t1), 1);
    assert_near(t0, 0.25, EPS);
    assert_near(t1, 0.5, EPS);
    /* negative direction */
    vv_ray rn = {{0.5, 1, 10}, {0, 0, -2}};
    assert_int_equal(vv_box_intersect_ray(b, rn, &t0, &t1), 1);
    assert_near(t0, 3.5, EPS);
    assert_near(t1, 5, EPS);
    /* origin inside: t0 negative, t1 positive */
    vv_ray ri = {{0.5, 1, 1}, {0, 1, 0}};
    assert_int_equal(vv_box_intersect_ray(b, ri, &t0, &t1), 1);
    assert_near(t0, -1, EPS);
    assert_near(t1, 1, EPS);
    /* misses: parallel outside, and oblique passing by */
    vv_ray m1 = {{-1, 2.5, 0.5}, {1, 0, 0}};
    assert_int_equal(vv_box_intersect_ray(b, m1, &t0, &t1), 0);
    vv_ray m2 = {{-1, -1, 0.5}, {1, -0.5, 0}};
    assert_int_equal(vv_box_intersect_ray(b, m2, &t0, &t1), 0);
    vv_ray m3 = {{2, 0, 0}, {1, 1, 1}};
    assert_int_equal(vv_box_intersect_ray(b, m3, &t0, &t1), 0);
    /* axis-parallel ray lying in a face plane touches the box */
    vv_ray f = {{-1, 2, 0.5}, {1, 0, 0}};
    assert_int_equal(vv_box_intersect_ray(b, f, &t0, &t1), 1);
    assert_near(t0, 1, EPS);
    assert_near(t1, 2, EPS);
    /* negative zero direction components are parallel, not -inf slabs */
    vv_ray nz = {{0.5, 0.5, -1}, {-0.0, -0.0, 1}};
    assert_int_equal(vv_box_intersect_ray(b, nz, &t0, &t1), 1);
    assert_near(t0, 1, EPS);
    assert_near(t1, 4, EPS);
    /* diagonal through opposite corners */
    vv_ray d = {{-1, -2, -3}, {1, 2, 3}};
    assert_int_equal(vv_box_intersect_ray(b, d, &t0, &t1), 1);
    assert_near(t0, 1, EPS);
    assert_near(t1, 2, EPS);
}

static int
inside_box(vv_box b, vv_vec3 p, double eps) {
    return p.x > b.min.x + eps && p.x < b.max.x - eps && p.y > b.min.y + eps &&
           p.y < b.max.y - eps && p.z > b.min.z + eps && p.z < b.max.z - eps;
}

static double
box_face_distance(vv_box b, vv_vec3 p) {
    double d = fabs(p.x - b.min.x);
    d = fmin(d, fabs(p.x - b.max.x));
    d = fmin(d, fabs(p.y - b.min.y));
    d = fmin(d, fabs(p.y - b.max.y));
    d = fmin(d, fabs(p.z - b.min.z));
    return fmin(d, fabs(p.z - b.max.z));
}

/* Random rays against brute-force marching. */
static void
test_box_ray_random(void **state) {
    (void)state;
    uint64_t seed = 2024;
    vv_box b = {{-1, 0.5, 2}, {3, 1.5, 4}};
    int hits = 0, misses = 0;
    for (int trial = 0; trial < 500; trial++) {
        vv_ray r = {rnd_vec(&seed, -4, 6), rnd_vec(&seed, -1, 1)};
        double t0 = 0, t1 = 0;
        int hit = vv_box_intersect_ray(b, r, &t0, &t1);
        if (hit) {
            hits++;
            assert_true(t0 <= t1);
            assert_true(box_face_distance(b, vv_ray_at(r, t0)) < 1e-9);
            assert_true(box_face_distance(b, vv_ray_at(r, t1)) < 1e-9);
            vv_vec3 m = vv_ray_at(r, 0.5 * (t0 + t1));
            assert_true(m.x >= b.min.x - 1e-9 && m.x <= b.max.x + 1e-9);
            assert_true(m.y >= b.min.y - 1e-9 && m.y <= b.max.y + 1e-9);
            assert_true(m.z >= b.min.z - 1e-9 && m.z <= b.max.z + 1e-9);
            /* just outside the interval is outside the box */
            assert_false(inside_box(b, vv_ray_at(r, t0 - 1e-6), 0));
            assert_false(inside_box(b, vv_ray_at(r, t1 + 1e-6), 0));
        } else {
            misses++;
            for (double t = -50; t <= 50; t += 0.01)
                if (inside_box(b, vv_ray_at(r, t), 1e-6))
                    fail_msg("missed ray passes through the box at t = %g", t);
        }
    }
    assert_true(hits > 20 && misses > 20); /* both branches exercised */
}

static void
test_box_transform(void **state) {
    (void)state;
    vv_box b = {{0, 0, 0}, {1, 1, 1}};
    vv_box t = vv_box_transform(b, vv_mat4_translate(vv_vec3_make(1, -2, 3)));
    assert_vec_near(t.min, vv_vec3_make(1, -2, 3), 0);
    assert_vec_near(t.max, vv_vec3_make(2, -1, 4), 0);
    vv_box r = vv_box_transform(b, vv_mat4_rotate(vv_vec3_make(0, 0, 1), VV_PI / 4));
    double h = sqrt(0.5);
    assert_vec_near(r.min, vv_vec3_make(-h, 0, 0), 1e-12);
    assert_vec_near(r.max, vv_vec3_make(h, 2 * h, 1), 1e-12);
    /* a negative scale swaps min and max */
    vv_box s = vv_box_transform(b, vv_mat4_scale(vv_vec3_make(-2, 1, 3)));
    assert_vec_near(s.min, vv_vec3_make(-2, 0, 0), 0);
    assert_vec_near(s.max, vv_vec3_make(0, 1, 3), 0);
}

static void
test_plane(void **state) {
    (void)state;
    vv_plane pl = vv_plane_from_point_normal(vv_vec3_make(0, 0, 2), vv_vec3_make(0, 0, 5));
    assert_vec_near(pl.n, vv_vec3_make(0, 0, 1), 0);
    assert_near(pl.d, -2, 0);
    assert_near(vv_plane_distance(pl, vv_vec3_make(7, -3, 5)), 3, EPS);
    assert_near(vv_plane_distance(pl, vv_vec3_make(0, 0, 0)), -2, EPS);
    /* oblique plane: distance is Euclidean */
    vv_plane ob = vv_plane_from_point_normal(vv_vec3_make(1, 1, 1), vv_vec3_make(1, 1, 1));
    assert_near(vv_plane_distance(ob, vv_vec3_make(2, 2, 2)), sqrt(3), EPS);
    assert_near(vv_plane_distance(ob, vv_vec3_make(0, 0, 3)), 0, EPS);

    /* ray along +z from z = 0 over [0, 10]: keeps z >= 2, i.e. [2, 10] */
    vv_ray up = {{0, 0, 0}, {0, 0, 1}};
    double t0 = 0, t1 = 10;
    assert_int_equal(vv_plane_clip_ray(pl, up, &t0, &t1), 1);
    assert_near(t0, 2, EPS);
    assert_near(t1, 10, EPS);
    /* ray along -z from z = 5 over [0, 10]: keeps [0, 3] */
    vv_ray down = {{0, 0, 5}, {0, 0, -1}};
    t0 = 0;
    t1 = 10;
    assert_int_equal(vv_plane_clip_ray(pl, down, &t0, &t1), 1);
    assert_near(t0, 0, EPS);
    assert_near(t1, 3, EPS);
    /* interval entirely on the removed side */
    t0 = 0;
    t1 = 1;
    assert_int_equal(vv_plane_clip_ray(pl, up, &t0, &t1), 0);
    /* a non-unit direction: t scales */
    vv_ray up2 = {{0, 0, 0}, {0, 0, 4}};
    t0 = 0;
    t1 = 10;
    assert_int_equal(vv_plane_clip_ray(pl, up2, &t0, &t1), 1);
    assert_near(t0, 0.5, EPS);
    /* parallel rays: kept whole on the kept side, dropped on the other */
    vv_ray par_in = {{0, 0, 3}, {1, 0, 0}};
    t0 = -1;
    t1 = 4;
    assert_int_equal(vv_plane_clip_ray(pl, par_in, &t0, &t1), 1);
    assert_near(t0, -1, 0);
    assert_near(t1, 4, 0);
    vv_ray par_out = {{0, 0, 1}, {1, 0, 0}};
    assert_int_equal(vv_plane_clip_ray(pl, par_out, &t0, &t1), 0);
    /* the kept part is where the normal points, checked by sampling */
    uint64_t seed = 5;
    for (int trial = 0; trial < 200; trial++) {
        vv_plane p = vv_plane_from_point_normal(rnd_vec(&seed, -1, 1), rnd_vec(&seed, -1, 1));
        vv_ray ray = {rnd_vec(&seed, -3, 3), rnd_vec(&seed, -1, 1)};
        double a = -5, c = 5;
        int keep = vv_plane_clip_ray(p, ray, &a, &c);
        for (double t = -5; t <= 5; t += 0.05) {
            double s = vv_plane_distance(p, vv_ray_at(ray, t));
            if (s > 1e-9)
                assert_true(keep && t >= a - 1e-9 && t <= c + 1e-9);
            if (s < -1e-9 && keep)
                assert_true(t < a + 1e-9 || t > c - 1e-9);
        }
    }
}

int
main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vec3),
        cmocka_unit_test(test_mat4_mul_identity_transpose),
        cmocka_unit_test(test_mat4_inverse_random),
        cmocka_unit_test(test_mat4_inverse_singular),
        cmocka_unit_test(test_mat4_inverse_numerically_singular),
        cmocka_unit_test(test_mat4_convention),
        cmocka_unit_test(test_mat4_rotate),
        cmocka_unit_test(test_mat4_look_at),
        cmocka_unit_test(test_mat4_perspective),
        cmocka_unit_test(test_mat4_orthographic),
        cmocka_unit_test(test_quat),
        cmocka_unit_test(test_quat_slerp),
        cmocka_unit_test(test_box_ray),
        cmocka_unit_test(test_box_ray_random),
        cmocka_unit_test(test_box_transform),
        cmocka_unit_test(test_plane),
    };
    return vt_run_tests(tests, NULL, NULL);
}
