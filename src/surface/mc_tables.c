/*
 * Marching Cubes case tables, generated at first use instead of typed in:
 * for each of the 256 corner cases and each decision (joined or separated)
 * of its ambiguous faces, the contour segments of the six faces are built,
 * oriented and linked into closed loops, and each loop is triangulated.
 *
 * Why generated: the classic 1987 table resolves ambiguous faces
 * inconsistently (holes). Here every face's segments depend on that face
 * alone (its corner signs and, when ambiguous, the asymptotic decider), so
 * the two cells sharing a face produce the same segments: no cracks, and
 * every segment edge of the mesh has exactly two triangles.
 *
 * Orientation: a segment on a face is directed so that, seen from outside
 * the cube along the face's outward normal n, the inside corners it cuts
 * off (value >= isovalue) lie to its right: ((q - p) x (c - p)) · n < 0 for
 * an inside corner c. The loops then run counter-clockwise seen from the
 * outside of the surface (the side of lower values).
 *
 * Triangulation: a fan from the first loop vertex whose diagonals join
 * edges that share no cube face. Such a diagonal lies in this cell only,
 * so no edge of the mesh can get a third triangle from a neighbouring cell
 * (a diagonal between two points of one face could also be chosen by the
 * cell across that face). A loop that passes twice through an ambiguous
 * face has no such fan (the tunnel configurations of Marching Cubes 33);
 * it is fanned around an extra vertex at the mean of its points, which
 * belongs to this cell alone.
 */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "surface_internal.h"

const int mc_edge_corner[12][2] = {{0, 1}, {1, 2}, {3, 2}, {0, 3}, {4, 5}, {5, 6},
                                   {7, 6}, {4, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
const int mc_face_corner[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                  {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 2, 6, 5}};
static const int face_normal[6][3] = {{0, 0, -1}, {0, 0, 1},  {0, -1, 0},
                                      {0, 1, 0},  {-1, 0, 0}, {1, 0, 0}};
static const int corner_pos[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                     {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/* A configuration count bound: sum over cases of 2^(ambiguous faces) is far below. */
#define MAX_CONFIGS 4096

static mc_tables tables;
static mc_config config_store[MAX_CONFIGS];
static pthread_once_t tables_once = PTHREAD_ONCE_INIT;
static int tables_ok;

static int
edge_of(int a, int b) {
    for (int e = 0; e < 12; e++)
        if ((mc_edge_corner[e][0] == a && mc_edge_corner[e][1] == b) ||
            (mc_edge_corner[e][0] == b && mc_edge_corner[e][1] == a))
            return e;
    return -1;
}

/* Bit f set when face f holds edge e. */
static int
edge_faces(int e) {
    int m = 0;
    for (int f = 0; f < 6; f++) {
        int n = 0;
        for (int q = 0; q < 4; q++)
            n += mc_face_corner[f][q] == mc_edge_corner[e][0] ||
                 mc_face_corner[f][q] == mc_edge_corner[e][1];
        if (n == 2)
            m |= 1 << f;
    }
    return m;
}

static void
edge_mid(int e, double p[3]) {
    for (int a = 0; a < 3; a++)
        p[a] = 0.5 * (corner_pos[mc_edge_corner[e][0]][a] + corner_pos[mc_edge_corner[e][1]][a]);
}

/* Directs segment (a, b) on face f so the test corner tc lies right of it when inside. */
static void
orient(int f, int *a, int *b, int tc, int tc_inside) {
    double p[3], q[3], c[3], u[3], w[3];
    edge_mid(*a, p);
    edge_mid(*b, q);
    for (int k = 0; k < 3; k++) {
        c[k] = corner_pos[tc][k];
        u[k] = q[k] - p[k];
        w[k] = c[k] - p[k];
    }
    double x[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    double s = x[0] * face_normal[f][0] + x[1] * face_normal[f][1] + x[2] * face_normal[f][2];
    if ((tc_inside && s > 0) || (!tc_inside && s < 0)) {
        int t = *a;
        *a = *b;
        *b = t;
    }
}

/* Builds the configuration of case cs with decision bits dec over its ambiguous faces. */
static int
build_config(int cs, int dec, mc_config *cfg) {
    int next[12];
    for (int e = 0; e < 12; e++)
        next[e] = -1;
    int amb_index = 0;
    for (int f = 0; f < 6; f++) {
        const int *q = mc_face_corner[f];
        int s[4], E[4], cross[4], nc = 0;
        for (int m = 0; m < 4; m++)
            s[m] = (cs >> q[m]) & 1;
        for (int m = 0; m < 4; m++) {
            E[m] = edge_of(q[m], q[(m + 1) & 3]);
            cross[m] = s[m] != s[(m + 1) & 3];
            nc += cross[m];
        }
        int seg[2][3], nseg = 0; /* edge a, edge b, test corner slot */
        if (nc == 2) {
            int m1 = -1, m2 = -1;
            for (int m = 0; m < 4; m++)
                if (cross[m]) {
                    if (m1 < 0)
                        m1 = m;
                    else
                        m2 = m;
                }
            int tc = 0;
            if (m2 == m1 + 1)
                tc = m2; /* common corner of E[m1] and E[m2] */
            else if (m1 == 0 && m2 == 3)
                tc = 0;
            seg[0][0] = E[m1];
            seg[0][1] = E[m2];
            seg[0][2] = tc;
            nseg = 1;
        } else if (nc == 4) {
            int joined = (dec >> amb_index) & 1;
            amb_index++;
            /* joined: the outside corners are cut off; separated: the inside ones */
            for (int m = 0; m < 4; m++)
                if (s[m] != joined) {
                    seg[nseg][0] = E[(m + 3) & 3];
                    seg[nseg][1] = E[m];
                    seg[nseg][2] = m;
                    nseg++;
                }
        }
        for (int k = 0; k < nseg; k++) {
            int a = seg[k][0], b = seg[k][1], tc = q[seg[k][2]];
            orient(f, &a, &b, tc, (cs >> tc) & 1);
            if (next[a] >= 0)
                return 0; /* two outgoing segments: inconsistent */
            next[a] = b;
        }
    }
    /* every crossing edge has one outgoing and one incoming segment */
    int incoming[12] = {0};
    for (int e = 0; e < 12; e++)
        if (next[e] >= 0)
            incoming[next[e]]++;
    for (int e = 0; e < 12; e++) {
        int crosses = ((cs >> mc_edge_corner[e][0]) & 1) != ((cs >> mc_edge_corner[e][1]) & 1);
        if (crosses != (next[e] >= 0) || incoming[e] != (next[e] >= 0))
            return 0;
    }
    int used[12] = {0};
    cfg->n_tri = 0;
    cfg->n_centre = 0;
    for (int e0 = 0; e0 < 12; e0++) {
        if (next[e0] < 0 || used[e0])
            continue;
        int loop[12], n = 0;
        for (int e = e0; !used[e]; e = next[e]) {
            used[e] = 1;
            loop[n++] = e;
        }
        if (n < 3)
            return 0;
        int start = -1;
        for (int st = 0; st < n && start < 0; st++) {
            int ok = 1;
            int fa = edge_faces(loop[st]);
            for (int j = 2; j <= n - 2 && ok; j++)
                if (fa & edge_faces(loop[(st + j) % n]))
                    ok = 0;
            if (ok)
                start = st;
        }
        if (start < 0) {
            /* a loop through an ambiguous face twice (the tunnels of MC33 cases 6, 7, 10,
             * 12, 13): fan around a vertex at the loop's centre, private to this cell */
            if (cfg->n_centre >= MC_MAX_CENTRE || cfg->n_tri + n > MC_MAX_TRI)
                return 0;
            int c = cfg->n_centre++;
            uint16_t mask = 0;
            for (int j = 0; j < n; j++)
                mask |= (uint16_t)(1u << loop[j]);
            cfg->centre_edges[c] = mask;
            for (int j = 0; j < n; j++) {
                uint8_t *t = cfg->tri[cfg->n_tri++];
                t[0] = (uint8_t)(12 + c);
                t[1] = (uint8_t)loop[j];
                t[2] = (uint8_t)loop[(j + 1) % n];
            }
            continue;
        }
        for (int j = 1; j <= n - 2; j++) {
            if (cfg->n_tri >= MC_MAX_TRI)
                return 0;
            uint8_t *t = cfg->tri[cfg->n_tri++];
            t[0] = (uint8_t)loop[start];
            t[1] = (uint8_t)loop[(start + j) % n];
            t[2] = (uint8_t)loop[(start + j + 1) % n];
        }
    }
    return 1;
}

static void
build_tables(void) {
    int nconf = 0;
    for (int cs = 0; cs < 256; cs++) {
        int na = 0;
        for (int f = 0; f < 6; f++) {
            const int *q = mc_face_corner[f];
            int s0 = (cs >> q[0]) & 1, s1 = (cs >> q[1]) & 1, s2 = (cs >> q[2]) & 1,
                s3 = (cs >> q[3]) & 1;
            if (s0 == s2 && s1 == s3 && s0 != s1)
                tables.amb_face[cs][na++] = (uint8_t)f;
        }
        tables.n_amb[cs] = (uint8_t)na;
        tables.base[cs] = (uint16_t)nconf;
        uint16_t em = 0;
        for (int e = 0; e < 12; e++)
            if (((cs >> mc_edge_corner[e][0]) & 1) != ((cs >> mc_edge_corner[e][1]) & 1))
                em |= (uint16_t)(1u << e);
        tables.edge_mask[cs] = em;
        for (int d = 0; d < (1 << na); d++) {
            if (nconf >= MAX_CONFIGS || !build_config(cs, d, &config_store[nconf]))
                return;
            nconf++;
        }
    }
    tables.n_configs = nconf;
    tables.configs = config_store;
    tables_ok = 1;
}

const mc_tables *
mc_tables_get(void) {
    pthread_once(&tables_once, build_tables);
    return tables_ok ? &tables : NULL;
}
