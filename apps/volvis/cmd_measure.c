/*
 * volvis measure INPUT [--iso V] [--seed P] [--method voxel|mc]
 *                [--histogram [--plot OUT.png]] [--distance P1 P2] [--json]
 *                [--channel C] [--time T] [--coloc C1,C2 [--mask M] [--thresholds TA,TB]]
 * The Measurement component on the command line: a readable table, or the
 * same numbers as JSON. INPUT is a volume, or a mesh (.ply .obj .stl .off),
 * for which area, enclosed volume, distances and the distance to another
 * mesh (--to) are measured.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli.h"

static const cli_opt_spec measure_opts[] = {
    {"iso", 0, "V"},
    {"seed", 0, "P"},
    {"method", 0, "voxel|mc"},
    {"histogram", 0, NULL},
    {"plot", 0, "OUT.png"},
    {"bins", 0, "N"},
    {"range", 0, "LO:HI"},
    {"log", 0, NULL},
    {"distance", 0, "P1 P2"}, /* rewritten from "--distance P1 P2" before parsing */
    {"geodesic", 0, "P1 P2"}, /* likewise */
    {"steiner", 0, "K"},
    {"roi", 0, "I0,J0,K0:I1,J1,K1"},
    {"cut", 0, "PX,PY,PZ:NX,NY,NZ"},
    {"to", 0, "MESH"},
    {"volume", 0, NULL},
    {"labels", 0, NULL},
    {"json", 0, NULL},
    {"threads", 0, "N"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"series", 0, "N"},
    {"channel", 0, "C"},
    {"time", 0, "T"},
    {"coloc", 0, "C1,C2"},
    {"mask", 0, "FILE"},
    {"thresholds", 0, "TA,TB"},
    {"memory-limit", 0, "SIZE"},
    {"quiet", 'q', NULL},
};
#define N_MEASURE_OPTS ((int)(sizeof measure_opts / sizeof measure_opts[0]))

void
cli_measure_usage(FILE *out) {
    fprintf(out,
            "usage: volvis measure [OPTIONS] INPUT\n"
            "\n"
            "Measures a volume or a mesh and prints a table (or JSON with --json). Lengths,\n"
            "areas and volumes are in world units (the file's unit, usually mm).\n"
            "\n"
            "Volumes:\n"
            "  --iso V          area and enclosed volume of the isosurface value == V (voxels\n"
            "                   >= V are inside)\n"
            "  --method mc|voxel  mc (default): Marching Cubes triangle area; volume by the\n"
            "                   divergence theorem, closed with caps where the volume (or\n"
            "                   --roi) boundary or a --cut plane cuts the surface. voxel:\n"
            "                   voxels >= V times the voxel volume; area from exposed voxel\n"
            "                   faces, which overestimates a smooth surface by about 1.5x\n"
            "                   (reported)\n"
            "  --seed P         only the surface-tracked section: the 6-connected region of\n"
            "                   voxels >= V that holds the voxel nearest to P (within 2 voxels)\n"
            "  --histogram      histogram of the voxel values (of --roi/--cut), as a table\n"
            "  --bins N         histogram bins, 1..100000 (default 32)\n"
            "  --range LO:HI    histogram range (default: the values' range)\n"
            "  --plot OUT.png   also draw the histogram as a PNG bar chart with axes\n"
            "  --log            logarithmic count axis in the plot\n"
            "  --labels         INPUT is a label volume (volvis filter --components): for\n"
            "                   each label its voxels, volume, centroid and bounding box\n"
            "  --channel C, --time T, --series N  measure this channel and time step of\n"
            "                   INPUT (from 0), this DICOM series\n"
            "  --coloc C1,C2    colocalisation of channels C1 and C2 (at --time T):\n"
            "                   Pearson's r and Manders' M1, M2 over the voxels where\n"
            "                   --mask FILE (a volume of the same size) is non-zero\n"
            "  --thresholds TA,TB  Manders: the channels' values above these count as\n"
            "                   signal (default 0,0: Manders' original coefficients)\n"
            "  --memory-limit SIZE  measure a volume larger than memory box by box within\n"
            "                   SIZE bytes (K, M, G): --iso (both --method) and --histogram\n"
            "                   of level 0 of a pyramid (OME-Zarr, BigDataViewer, Imaris, a\n"
            "                   .vvb with levels) or of a .vvb, raw (--raw) or uncompressed\n"
            "                   NRRD read by bricks; the whole volume's numbers (to rounding);\n"
            "                   not with --seed, --roi, --cut, --geodesic, --labels, --coloc\n"
            "  --roi I0,J0,K0:I1,J1,K1  restrict to this voxel box (inclusive)\n"
            "  --cut PX,PY,PZ:NX,NY,NZ  keep the side of this world plane the normal points to\n"
            "                   (repeatable, up to 8; histogram and both --method)\n"
            "Meshes (.ply .obj .stl .off):\n"
            "  area, whether the mesh is closed, and its enclosed volume when it is;\n"
            "  --volume         require the volume: an open mesh is an error (exit 1)\n"
            "  --to MESH        the minimum distance to another mesh, with the closest points\n"
            "Both:\n"
            "  --distance P1 P2  distance between two points (two arguments)\n"
            "  --json           print JSON instead of the table\n"
            "  --threads N      threads (default: all cores)\n"
            "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]  read INPUT as raw voxels\n"
            "  -h, --help       show this help\n"
            "\n"
            "A point P is X,Y,Z in world coordinates, or voxel:I,J,K in voxel indices\n"
            "(fractional allowed).\n"
            "\n"
            "Examples:\n"
            "  volvis measure ../shared/data/volumes/ct_head.nrrd --iso 300\n"
            "  volvis measure ct_head.nrrd --iso 300 --method voxel --json\n"
            "  volvis measure ct_head.nrrd --iso 300 --seed voxel:128,60,54\n"
            "  volvis measure ct_head.nrrd --histogram --bins 64 --plot hist.png --log\n"
            "  volvis measure ct_head.nrrd --distance voxel:0,0,0 voxel:255,255,107\n"
            "  volvis measure ../shared/data/meshes/bunny.ply --to other.stl\n"
            "  volvis measure cells.ome.tif --channel 1 --histogram\n"
            "  volvis measure big.ome.zarr --memory-limit 1G --iso 300 --histogram\n"
            "  volvis measure cells.ome.tif --coloc 0,1 --thresholds 120,90 --mask nuclei.nrrd\n");
}

#if defined(__SANITIZE_ADDRESS__)
/* Sanitizer builds (the suppressions of the whole volvis program): cairo's
 * text rendering (the --plot labels) leaves fontconfig's process-wide caches
 * allocated at exit, a library cache, not a leak; Teem's gzip writer leaks
 * its zlib stream when a write fails (a full disk, a file size limit:
 * test_apps_atomic_writes), as its reader does on a truncated stream
 * (tests/lsan.supp), and the program then exits; Mesa 22.3's lavapipe (the
 * Vulkan device of the gpu renderer in the tests, `volvis serve` of a scene
 * naming gpu among them) keeps allocations of its JIT-compiled shaders
 * (LLVM 15) past vkDestroyDevice (tests/lsan.supp). */
const char *__lsan_default_suppressions(void);
const char *
__lsan_default_suppressions(void) {
    return "leak:libfontconfig.so\nleak:_nrrdGzOpen\nleak:libvulkan_lvp.so\nleak:libLLVM-15.so\n";
}
/* and no table of the suppressions used after an error: stderr stays one line */
const char *__lsan_default_options(void);
const char *
__lsan_default_options(void) {
    return "print_suppressions=0";
}
#endif

static int
is_mesh_file(const char *path) {
    static const char *ext[] = {".ply", ".obj", ".stl", ".off"};
    size_t n = strlen(path);
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (n > 4 && strcasecmp(path + n - 4, ext[i]) == 0)
            return 1;
    return 0;
}

/* JSON string with escapes. */
static void
json_str(const char *s) {
    putchar('"');
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            printf("\\%c", c);
        else if (c < 0x20)
            printf("\\u%04x", c);
        else
            putchar(c);
    }
    putchar('"');
}

/* A number as JSON (null when not finite). */
static void
json_num(double x) {
    if (isfinite(x))
        printf("%.10g", x);
    else
        printf("null");
}

static const char *
unit_of(vv_unit u) {
    return u == VV_UNIT_UNKNOWN ? "units" : vv_unit_name(u);
}

/* --labels: one line (or JSON object) per label of a label volume. */
static int
measure_labels(const char *in, const vv_raw_params *raw, int json) {
    vv_volume *v;
    int rc = cli_load_volume(in, raw, &v);
    if (rc)
        return rc;
    vv_label_stats *s = NULL;
    int n = 0;
    vv_error_clear();
    vv_status st = vv_measure_labels(v, &s, &n);
    if (st != VV_OK) {
        vv_volume_free(v);
        return cli_fail(st, in);
    }
    const char *u = v->unit == VV_UNIT_UNKNOWN ? "units" : vv_unit_name(v->unit);
    if (json) {
        printf("{\"file\": ");
        json_str(in);
        printf(", \"unit\": \"%s\", \"labels\": [", u);
        for (int i = 0; i < n; i++)
            printf("%s\n  {\"label\": %u, \"voxels\": %llu, \"volume\": %.10g, \"centroid\": "
                   "[%.10g, %.10g, %.10g], \"box_min\": [%d, %d, %d], \"box_max\": [%d, %d, %d]}",
                   i ? "," : "", s[i].label, (unsigned long long)s[i].voxels, s[i].volume,
                   s[i].centroid.x, s[i].centroid.y, s[i].centroid.z, s[i].box_min[0],
                   s[i].box_min[1], s[i].box_min[2], s[i].box_max[0], s[i].box_max[1],
                   s[i].box_max[2]);
        printf("]}\n");
    } else {
        printf("labels:       %d in %s\n", n, in);
        printf("%8s %10s %14s  %-32s %s\n", "label", "voxels", "volume", "centroid", "voxel box");
        for (int i = 0; i < n; i++) {
            char c[64];
            snprintf(c, sizeof c, "%.4g, %.4g, %.4g", s[i].centroid.x, s[i].centroid.y,
                     s[i].centroid.z);
            printf("%8u %10llu %14.6g  %-32s %d,%d,%d:%d,%d,%d\n", s[i].label,
                   (unsigned long long)s[i].voxels, s[i].volume, c, s[i].box_min[0],
                   s[i].box_min[1], s[i].box_min[2], s[i].box_max[0], s[i].box_max[1],
                   s[i].box_max[2]);
        }
        printf("(volumes in %s^3, centroids in world coordinates)\n", u);
    }
    free(s);
    vv_volume_free(v);
    return CLI_EXIT_OK;
}

typedef struct measure_req {
    int json, histogram, log, bins, threads, want_volume;
    uint64_t memory_limit;     /* --memory-limit: box by box (0: in memory) */
    int series, channel, time; /* which series, channel and time step of INPUT (-1: 0) */
    int coloc[2];              /* --coloc C1,C2 (-1: none) */
    double thresholds[2];
    const char *mask;
    int has_iso, has_seed, seed_voxel, has_range;
    double iso, seed[3], lo, hi;
    vv_measure_method method;
    const char *plot, *to;
    int has_distance, dvox[2];
    double dp[2][3];
    int has_geodesic, gvox[2], steiner;
    double gp[2][3];
    vv_roi region;
} measure_req;

static int
measure_mesh(const char *in, const measure_req *r) {
    vv_mesh *m = NULL, *other = NULL;
    vv_status s = vv_mesh_load(&m, in);
    if (s != VV_OK)
        return cli_fail(s, in);
    vv_mesh_topology t;
    if ((s = vv_mesh_topology_compute(m, &t)) != VV_OK) {
        vv_mesh_free(m);
        return cli_fail(s, in);
    }
    double area = vv_mesh_area(m), vol = NAN;
    vv_error_clear();
    vv_status vs = vv_measure_mesh_volume(m, &vol);
    if (vs != VV_OK && r->want_volume) {
        int rc = cli_fail(vs, in);
        vv_mesh_free(m);
        return rc;
    }
    double dist = NAN, md = NAN, pd[2][3] = {{0}};
    vv_vec3 pa = {0, 0, 0}, pb = {0, 0, 0};
    if (r->has_distance) {
        for (int i = 0; i < 2; i++)
            if (r->dvox[i]) {
                vv_mesh_free(m);
                cli_error("%s: voxel:I,J,K points need a volume, not a mesh", in);
                return CLI_EXIT_USAGE;
            }
        vv_measure_distance(NULL, vv_vec3_make(r->dp[0][0], r->dp[0][1], r->dp[0][2]), 0,
                            vv_vec3_make(r->dp[1][0], r->dp[1][1], r->dp[1][2]), 0, &dist);
        memcpy(pd, r->dp, sizeof pd);
    }
    if (r->to) {
        if ((s = vv_mesh_load(&other, r->to)) != VV_OK ||
            (s = vv_measure_mesh_distance(m, other, r->threads, &md, &pa, &pb)) != VV_OK) {
            int rc = cli_fail(s, r->to);
            vv_mesh_free(m);
            vv_mesh_free(other);
            return rc;
        }
    }
    if (r->json) {
        printf("{\"input\": ");
        json_str(in);
        printf(", \"kind\": \"mesh\", \"unit\": \"units\", \"vertices\": %zu, \"triangles\": %zu, "
               "\"area\": ",
               m->n_vertices, m->n_triangles);
        json_num(area);
        printf(", \"closed\": %s, \"boundary_edges\": %zu, \"volume\": ",
               t.closed && t.oriented ? "true" : "false", t.n_boundary_edges);
        json_num(vol);
        if (r->has_distance) {
            printf(", \"distance\": {\"p1\": [%.10g, %.10g, %.10g], \"p2\": [%.10g, %.10g, "
                   "%.10g], \"value\": ",
                   pd[0][0], pd[0][1], pd[0][2], pd[1][0], pd[1][1], pd[1][2]);
            json_num(dist);
            printf("}");
        }
        if (r->to) {
            printf(", \"mesh_distance\": {\"to\": ");
            json_str(r->to);
            printf(", \"value\": ");
            json_num(md);
            printf(", \"point\": [%.10g, %.10g, %.10g], \"point_to\": [%.10g, %.10g, %.10g]}", pa.x,
                   pa.y, pa.z, pb.x, pb.y, pb.z);
        }
        printf("}\n");
    } else {
        printf("%-22s %s (mesh, %zu vertices, %zu triangles)\n", "input", in, m->n_vertices,
               m->n_triangles);
        printf("%-22s %.10g units^2\n", "surface area", area);
        if (vs == VV_OK)
            printf("%-22s %.10g units^3 (closed mesh, divergence theorem)\n", "enclosed volume",
                   vol);
        else
            printf("%-22s not defined: open mesh (%zu boundary edges, %zu non-manifold)\n",
                   "enclosed volume", t.n_boundary_edges, t.n_nonmanifold_edges);
        if (r->has_distance)
            printf("%-22s %.10g units between (%g, %g, %g) and (%g, %g, %g)\n", "distance", dist,
                   pd[0][0], pd[0][1], pd[0][2], pd[1][0], pd[1][1], pd[1][2]);
        if (r->to)
            printf("%-22s %.10g units to %s, closest points (%g, %g, %g) and (%g, %g, %g)\n",
                   "minimum distance", md, r->to, pa.x, pa.y, pa.z, pb.x, pb.y, pb.z);
    }
    vv_mesh_free(m);
    vv_mesh_free(other);
    return CLI_EXIT_OK;
}

/* What measure_volume found. */
typedef struct volume_results {
    vv_isosurface_measure im;
    vv_histogram *h;
    double dist, dw[2][3]; /* --distance: the distance and its points (world) */
    double geo;            /* --geodesic: the distance and the surface points */
    vv_vec3 gon[2];
} volume_results;

/* The isosurface options of @p r for @p v: region, threads, the seed
 * (given in world units unless --seed-voxel) in index coordinates. */
static void
iso_options(const measure_req *r, const vv_volume *v, vv_isosurface_measure_options *o) {
    vv_isosurface_measure_options_init(o);
    o->method = r->method;
    o->region = r->region;
    o->threads = r->threads;
    if (r->has_seed) {
        o->has_seed = 1;
        vv_vec3 p = vv_vec3_make(r->seed[0], r->seed[1], r->seed[2]);
        if (!r->seed_voxel)
            p = vv_mat4_mul_point(vv_volume_world_to_index(v), p);
        o->seed[0] = p.x;
        o->seed[1] = p.y;
        o->seed[2] = p.z;
    }
}

/* The geodesic distance along the isosurface between the two points of
 * --geodesic (voxel points taken to world units). */
static vv_status
measure_geodesic(const measure_req *r, const vv_volume *v, volume_results *res) {
    vv_isosurface_measure_options o, d;
    iso_options(r, v, &o);
    vv_isosurface_measure_options_init(&d);
    o.method = d.method; /* the mesh is Marching Cubes' whatever --method says */
    vv_mat4 M = vv_volume_index_to_world(v);
    vv_vec3 gp[2];
    for (int i = 0; i < 2; i++) {
        gp[i] = vv_vec3_make(r->gp[i][0], r->gp[i][1], r->gp[i][2]);
        if (r->gvox[i])
            gp[i] = vv_mat4_mul_point(M, gp[i]);
    }
    vv_mesh *gm = NULL;
    vv_status s;
    if ((s = vv_measure_isosurface_mesh(&gm, v, r->iso, &o)) == VV_OK)
        s = vv_measure_geodesic(gm, gp[0], gp[1], r->steiner, &res->geo, &res->gon[0],
                                &res->gon[1]);
    vv_mesh_free(gm);
    return s;
}

/* --distance: the two points in world units (from @p v's voxels when so
 * given) and their distance. */
static void
measure_points(const measure_req *r, const vv_volume *v, volume_results *res) {
    if (!r->has_distance)
        return;
    vv_mat4 M = vv_volume_index_to_world(v);
    for (int i = 0; i < 2; i++) {
        vv_vec3 p = vv_vec3_make(r->dp[i][0], r->dp[i][1], r->dp[i][2]);
        if (r->dvox[i])
            p = vv_mat4_mul_point(M, p);
        res->dw[i][0] = p.x;
        res->dw[i][1] = p.y;
        res->dw[i][2] = p.z;
    }
    vv_measure_distance(NULL, vv_vec3_make(res->dw[0][0], res->dw[0][1], res->dw[0][2]), 0,
                        vv_vec3_make(res->dw[1][0], res->dw[1][1], res->dw[1][2]), 0, &res->dist);
}

/* The measurements @p r asks of @p v; on failure the message names the
 * file that failed in *@p fail_path. */
static vv_status
measure_compute(const char *in, const measure_req *r, const vv_volume *v, volume_results *res,
                const char **fail_path) {
    vv_status s;
    *fail_path = in;
    if (r->has_iso) {
        vv_isosurface_measure_options o;
        iso_options(r, v, &o);
        if ((s = vv_measure_isosurface(&res->im, v, r->iso, &o)) != VV_OK)
            return s;
    }
    if (r->has_geodesic && (s = measure_geodesic(r, v, res)) != VV_OK)
        return s;
    if (r->histogram) {
        if ((s = vv_measure_histogram(&res->h, v, r->bins, r->has_range ? r->lo : 0,
                                      r->has_range ? r->hi : 0, &r->region)) != VV_OK)
            return s;
        if (r->plot && (s = vv_histogram_plot_png(res->h, r->plot, 900, 560,
                                                  strrchr(in, '/') ? strrchr(in, '/') + 1 : in,
                                                  "value", r->log)) != VV_OK) {
            *fail_path = r->plot;
            return s;
        }
    }
    measure_points(r, v, res);
    return VV_OK;
}

/* The results as one JSON object on stdout. */
static void
print_volume_json(const char *in, const measure_req *r, const vv_volume *v,
                  const volume_results *res) {
    const char *u = unit_of(v->unit);
    const char *mname = r->method == VV_MEASURE_VOXEL ? "voxel" : "mc";
    const vv_isosurface_measure im = res->im;
    const vv_histogram *h = res->h;
    const double geo = res->geo, dist = res->dist;
    const vv_vec3 *gon = res->gon;
    const double(*dw)[3] = res->dw;
    printf("{\"input\": ");
    json_str(in);
    printf(", \"kind\": \"volume\", \"dims\": [%d, %d, %d], \"spacing\": [%.10g, %.10g, "
           "%.10g], \"unit\": \"%s\"",
           v->dims[0], v->dims[1], v->dims[2], v->spacing[0], v->spacing[1], v->spacing[2], u);
    if (r->has_iso) {
        printf(", \"isosurface\": {\"isovalue\": %.10g, \"method\": \"%s\", \"area\": ", r->iso,
               mname);
        json_num(im.area);
        printf(", \"volume\": ");
        json_num(im.volume);
        printf(", \"cut_area\": ");
        json_num(im.cut_area);
        printf(", \"voxels\": %llu, \"triangles\": %zu, \"area_bias\": %g",
               (unsigned long long)im.voxels, im.n_triangles, im.area_bias);
        if (r->has_seed)
            printf(", \"seed_voxel\": [%d, %d, %d]", im.seed_voxel[0], im.seed_voxel[1],
                   im.seed_voxel[2]);
        if (r->has_geodesic) {
            printf(", \"geodesic\": {\"p1\": [%.10g, %.10g, %.10g], \"p2\": [%.10g, %.10g, "
                   "%.10g], \"steiner\": %d, \"value\": ",
                   gon[0].x, gon[0].y, gon[0].z, gon[1].x, gon[1].y, gon[1].z, r->steiner);
            json_num(geo);
            printf("}");
        }
        printf("}");
    }
    if (h) {
        printf(", \"histogram\": {\"lo\": %.10g, \"hi\": %.10g, \"bins\": %d, \"total\": %llu, "
               "\"outside\": %llu, \"nan\": %llu, \"min\": ",
               h->lo, h->hi, h->nbins, (unsigned long long)h->total, (unsigned long long)h->outside,
               (unsigned long long)h->nan);
        json_num(h->min);
        printf(", \"max\": ");
        json_num(h->max);
        printf(", \"mean\": ");
        json_num(h->mean);
        printf(", \"sd\": ");
        json_num(h->sd);
        printf(", \"counts\": [");
        for (int b = 0; b < h->nbins; b++)
            printf("%s%llu", b ? ", " : "", (unsigned long long)h->counts[b]);
        printf("]");
        if (r->plot) {
            printf(", \"plot\": ");
            json_str(r->plot);
        }
        printf("}");
    }
    if (r->has_distance) {
        printf(", \"distance\": {\"p1\": [%.10g, %.10g, %.10g], \"p2\": [%.10g, %.10g, "
               "%.10g], \"value\": ",
               dw[0][0], dw[0][1], dw[0][2], dw[1][0], dw[1][1], dw[1][2]);
        json_num(dist);
        printf("}");
    }
    printf("}\n");
}

/* The results as aligned text on stdout. */
static void
print_volume_text(const char *in, const measure_req *r, const vv_volume *v,
                  const volume_results *res) {
    const char *u = unit_of(v->unit);
    const vv_isosurface_measure im = res->im;
    const vv_histogram *h = res->h;
    const double geo = res->geo, dist = res->dist;
    const vv_vec3 *gon = res->gon;
    const double(*dw)[3] = res->dw;
    printf("%-22s %s (%d x %d x %d %s, spacing %g x %g x %g %s)\n", "input", in, v->dims[0],
           v->dims[1], v->dims[2], vv_voxel_type_name(v->type), v->spacing[0], v->spacing[1],
           v->spacing[2], u);
    if (r->has_iso) {
        printf("%-22s %g (inside: values >= %g)\n", "isovalue", r->iso, r->iso);
        if (r->has_seed)
            printf("%-22s surface-tracked section from voxel (%d, %d, %d)\n", "region",
                   im.seed_voxel[0], im.seed_voxel[1], im.seed_voxel[2]);
        if (r->method == VV_MEASURE_MC) {
            printf("%-22s Marching Cubes (%zu triangles)\n", "method", im.n_triangles);
            printf("%-22s %.10g %s^2\n", "surface area", im.area, u);
            printf("%-22s %.10g %s^3 (divergence theorem, closed by %.6g %s^2 of caps)\n",
                   "enclosed volume", im.volume, u, im.cut_area, u);
        } else {
            printf("%-22s voxel counting\n", "method");
            printf("%-22s %.10g %s^2 (exposed voxel faces: about %.2gx the smooth surface)\n",
                   "surface area", im.area, u, im.area_bias);
            printf("%-22s %.10g %s^3 (%llu voxels)\n", "enclosed volume", im.volume, u,
                   (unsigned long long)im.voxels);
            if (im.cut_area > 0)
                printf("%-22s %.10g %s^2 of voxel faces on the region's boundary\n", "cut",
                       im.cut_area, u);
        }
        if (r->method == VV_MEASURE_MC)
            printf("%-22s %llu\n", "voxels inside", (unsigned long long)im.voxels);
        if (r->has_geodesic)
            printf("%-22s %.10g %s along the surface between (%g, %g, %g) and (%g, %g, %g) "
                   "(Steiner graph, %d points per edge)\n",
                   "geodesic distance", geo, u, gon[0].x, gon[0].y, gon[0].z, gon[1].x, gon[1].y,
                   gon[1].z, r->steiner);
    }
    if (h) {
        printf("%-22s %llu voxels (%llu outside the range, %llu NaN), min %g, max %g, mean "
               "%.6g, sd %.6g\n",
               "histogram", (unsigned long long)h->total, (unsigned long long)h->outside,
               (unsigned long long)h->nan, h->min, h->max, h->mean, h->sd);
        uint64_t cmax = 1;
        for (int b = 0; b < h->nbins; b++)
            cmax = h->counts[b] > cmax ? h->counts[b] : cmax;
        double w = (h->hi - h->lo) / h->nbins;
        for (int b = 0; b < h->nbins; b++) {
            int bar = (int)(40.0 * (double)h->counts[b] / (double)cmax + 0.5);
            printf("  [%12.6g, %12.6g%c %12llu  ", h->lo + b * w, h->lo + (b + 1) * w,
                   b == h->nbins - 1 ? ']' : ')', (unsigned long long)h->counts[b]);
            for (int q = 0; q < bar; q++)
                putchar('#');
            putchar('\n');
        }
        if (r->plot)
            printf("%-22s %s\n", "plot", r->plot);
    }
    if (r->has_distance)
        printf("%-22s %.10g %s between (%g, %g, %g) and (%g, %g, %g) (world)\n", "distance", dist,
               u, dw[0][0], dw[0][1], dw[0][2], dw[1][0], dw[1][1], dw[1][2]);
}

/* --memory-limit: the isosurface and the histogram of the whole volume read
 * box by box, through its pyramid (level 0) or by bricks. */
static int
measure_out_of_core(const char *in, const vv_raw_params *raw, const measure_req *r) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = VV_OPEN_OUT_OF_CORE_ONLY;
    oo.levels = 1; /* a pyramid: level 0 through its chunks */
    oo.load.channel = r->channel < 0 ? 0 : r->channel;
    oo.load.time = r->time;
    if (raw) {
        oo.load.format = VV_FORMAT_RAW;
        oo.load.has_raw = 1;
        oo.load.raw = *raw;
    }
    vv_cache_set_limit(vv_cache_process(), r->memory_limit);
    vv_opened od;
    vv_error_clear();
    vv_status s = vv_open(&od, in, &oo);
    if (s == VV_ERR_UNSUPPORTED || (s == VV_OK && od.kind != VV_DATA_VOLUME)) {
        vv_opened_clear(&od);
        cli_error("%s: cannot be read out of core (by bricks: .vvb, raw or uncompressed NRRD, "
                  "channel 0 at step 0; by levels: a pyramid); convert it to .vvb first (volvis "
                  "convert IN OUT.vvb)",
                  in);
        return CLI_EXIT_FAIL;
    }
    if (s != VV_OK)
        return cli_fail(s, in);
    const vv_volume *hdr = vv_source_level(od.source, 0);
    vv_box_reader read = vv_source_box;
    void *ctx = od.source;
    volume_results res;
    memset(&res, 0, sizeof res);
    res.dist = res.geo = NAN;
    const char *fail_path = in;
    if (r->threads > 0)
        vv_threads_set(r->threads);
    if (r->has_iso)
        s = vv_measure_isosurface_boxes(&res.im, hdr, read, ctx, r->iso, r->method, NULL);
    if (s == VV_OK && r->histogram)
        s = vv_measure_histogram_boxes(&res.h, hdr, read, ctx, r->bins, r->has_range ? r->lo : 0,
                                       r->has_range ? r->hi : 0, NULL);
    if (s == VV_OK && r->histogram && r->plot &&
        (s = vv_histogram_plot_png(res.h, r->plot, 900, 560,
                                   strrchr(in, '/') ? strrchr(in, '/') + 1 : in, "value",
                                   r->log)) != VV_OK)
        fail_path = r->plot;
    int rc;
    if (s != VV_OK) {
        rc = cli_fail(s, fail_path);
    } else {
        measure_points(r, hdr, &res);
        vv_source_stats st;
        vv_source_stats_get(od.source, &st);
        const double mib = (double)st.bytes_read / 1048576.0;
        const double peak = (double)st.peak_bytes / 1048576.0;
        if (r->json) {
            print_volume_json(in, r, hdr, &res);
        } else {
            print_volume_text(in, r, hdr, &res);
            printf("%-22s out of core, box by box: %.1f MiB read, peak cache %.1f of %.0f MiB\n",
                   "read", mib, peak, (double)r->memory_limit / 1048576.0);
        }
        rc = CLI_EXIT_OK;
    }
    vv_histogram_free(res.h);
    vv_opened_clear(&od);
    return rc;
}

static int
measure_volume(const char *in, const vv_raw_params *raw, const measure_req *r) {
    if (r->memory_limit)
        return measure_out_of_core(in, raw, r);
    vv_volume *v;
    int rc;
    if ((rc = cli_load_volume_sc(in, raw, r->series, r->channel, r->time, NULL, &v)))
        return rc;
    volume_results res;
    memset(&res, 0, sizeof res);
    res.dist = res.geo = NAN;
    const char *fail_path = in;
    vv_status s = measure_compute(in, r, v, &res, &fail_path);
    if (s != VV_OK) {
        rc = cli_fail(s, fail_path);
    } else {
        if (r->json)
            print_volume_json(in, r, v, &res);
        else
            print_volume_text(in, r, v, &res);
        rc = CLI_EXIT_OK;
    }
    vv_histogram_free(res.h);
    vv_volume_free(v);
    return rc;
}

/* "--distance P1 P2" and "--geodesic P1 P2" take two arguments: joined for
 * the parser into "--distance=P1;P2". *@p av (malloc'ed) is the new argument
 * list, @p joined the strings made (free both). Returns 0 or an exit status. */
static int
join_point_args(int argc, char **argv, char ***av_out, int *ac_out, char *joined[2]) {
    char **av = malloc(((size_t)argc + 1) * sizeof *av);
    if (!av) {
        cli_error("out of memory");
        return CLI_EXIT_FAIL;
    }
    int ac = 0;
    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--distance") != 0 && strcmp(argv[i], "--geodesic") != 0) {
            av[ac++] = argv[i];
            continue;
        }
        int g = argv[i][2] == 'g';
        if (i + 2 >= argc) {
            free(av);
            cli_error("measure: %s needs two points P1 P2 (see 'volvis measure --help')", argv[i]);
            return CLI_EXIT_USAGE;
        }
        free(joined[g]);
        size_t n = strlen(argv[i + 1]) + strlen(argv[i + 2]) + 16;
        if (!(joined[g] = malloc(n))) {
            free(av);
            return CLI_EXIT_FAIL;
        }
        snprintf(joined[g], n, "%s=%s;%s", argv[i], argv[i + 1], argv[i + 2]);
        av[ac++] = joined[g];
        i += 2;
    }
    av[ac] = NULL;
    *av_out = av;
    *ac_out = ac;
    return 0;
}

/* The two points "P1;P2" of option @p opt (as join_point_args made it). */
static int
parse_two_points(const cli_args *a, const char *opt, const char *s, double p[2][3], int vox[2]) {
    const char *semi = strchr(s, ';');
    char p1[256];
    size_t n1 = semi ? (size_t)(semi - s) : 0;
    if (!semi || n1 >= sizeof p1)
        return cli_usage_error(a, "--%s needs two points P1 P2", opt);
    memcpy(p1, s, n1);
    p1[n1] = '\0';
    int rc = cli_parse_point(a, opt, p1, p[0], &vox[0]);
    return rc ? rc : cli_parse_point(a, opt, semi + 1, p[1], &vox[1]);
}

/* The isosurface, histogram and region options into @p r. */
static int
parse_volume_options(cli_args *a, measure_req *r) {
    const char *s;
    int rc;
    if ((s = cli_get(a, "iso"))) {
        r->has_iso = 1;
        if ((rc = cli_parse_double(a, "iso", s, -HUGE_VAL, HUGE_VAL, &r->iso)))
            return rc;
    }
    if ((s = cli_get(a, "seed"))) {
        r->has_seed = 1;
        if ((rc = cli_parse_point(a, "seed", s, r->seed, &r->seed_voxel)))
            return rc;
        if (!r->has_iso)
            return cli_usage_error(a, "--seed needs --iso");
    }
    if ((s = cli_get(a, "method"))) {
        if (!strcmp(s, "voxel"))
            r->method = VV_MEASURE_VOXEL;
        else if (strcmp(s, "mc"))
            return cli_usage_error(a, "--method: expected voxel or mc, got '%s'", s);
    }
    if ((s = cli_get(a, "bins")) && (rc = cli_parse_int(a, "bins", s, 1, 100000, &r->bins)))
        return rc;
    if ((s = cli_get(a, "range"))) {
        r->has_range = 1;
        if ((rc = cli_parse_range(a, "range", s, &r->lo, &r->hi)))
            return rc;
    }
    if ((r->plot || cli_get(a, "bins") || cli_get(a, "range") || r->log) && !r->histogram)
        return cli_usage_error(a, "--plot, --bins, --range and --log go with --histogram");
    if ((s = cli_get(a, "threads")) && (rc = cli_parse_int(a, "threads", s, 0, 4096, &r->threads)))
        return rc;
    if ((s = cli_get(a, "roi")) &&
        (rc = cli_parse_roi(a, "roi", s, r->region.roi_min, r->region.roi_max)))
        return rc;
    for (int i = 0; i < a->n_seen; i++) {
        if (strcmp(a->specs[a->seen[i].opt].name, "cut"))
            continue;
        if (r->region.n_cut_planes == VV_MAX_CUT_PLANES)
            return cli_usage_error(a, "--cut: at most %d planes", VV_MAX_CUT_PLANES);
        if ((rc = cli_parse_plane(a, "cut", a->seen[i].value,
                                  &r->region.cut_planes[r->region.n_cut_planes++])))
            return rc;
    }
    return 0;
}

/* --distance, --steiner and --geodesic into @p r. */
static int
parse_point_options(cli_args *a, measure_req *r) {
    const char *s;
    int rc;
    if ((s = cli_get(a, "distance"))) {
        r->has_distance = 1;
        if ((rc = parse_two_points(a, "distance", s, r->dp, r->dvox)))
            return rc;
    }
    r->steiner = 8;
    if ((s = cli_get(a, "steiner")) && (rc = cli_parse_int(a, "steiner", s, 0, 64, &r->steiner)))
        return rc;
    if ((s = cli_get(a, "geodesic"))) {
        r->has_geodesic = 1;
        if ((rc = parse_two_points(a, "geodesic", s, r->gp, r->gvox)))
            return rc;
        if (!r->has_iso)
            return cli_usage_error(a, "--geodesic needs --iso (the surface to follow)");
        if (r->method == VV_MEASURE_VOXEL)
            return cli_usage_error(a, "--geodesic follows the Marching Cubes surface (not with "
                                      "--method voxel)");
    }
    return 0;
}

/* --coloc C1,C2: Pearson's r and Manders' M1, M2 of two channels of INPUT. */
static int
measure_coloc(const char *in, const vv_raw_params *raw, const measure_req *r) {
    vv_volume *v[2] = {NULL, NULL}, *mask = NULL;
    int rc = 0;
    for (int c = 0; c < 2 && !rc; c++)
        rc = cli_load_volume_sc(in, raw, r->series, r->coloc[c], r->time, NULL, &v[c]);
    if (!rc && r->mask)
        rc = cli_load_volume(r->mask, NULL, &mask);
    vv_colocalisation co;
    vv_status s = VV_OK;
    if (!rc) {
        vv_error_clear();
        s = vv_measure_colocalisation(v[0], v[1], mask, r->thresholds[0], r->thresholds[1], &co);
        if (s != VV_OK)
            rc = cli_fail(s, in);
    }
    if (!rc && r->json) {
        printf("{\"file\": ");
        json_str(in);
        printf(", \"channels\": [%d, %d], \"time\": %d, \"mask\": ", r->coloc[0], r->coloc[1],
               r->time < 0 ? 0 : r->time);
        if (r->mask)
            json_str(r->mask);
        else
            printf("null");
        printf(", \"voxels\": %llu, \"pearson\": ", (unsigned long long)co.voxels);
        json_num(co.pearson);
        printf(", \"manders_m1\": ");
        json_num(co.manders_m1);
        printf(", \"manders_m2\": ");
        json_num(co.manders_m2);
        printf(", \"thresholds\": [");
        json_num(co.threshold[0]);
        printf(", ");
        json_num(co.threshold[1]);
        printf("], \"means\": [");
        json_num(co.mean[0]);
        printf(", ");
        json_num(co.mean[1]);
        printf("]}\n");
    } else if (!rc) {
        printf("%-22s %s, channels %d and %d, time step %d\n", "colocalisation", in, r->coloc[0],
               r->coloc[1], r->time < 0 ? 0 : r->time);
        printf("%-22s %s\n", "mask", r->mask ? r->mask : "none (every voxel)");
        printf("%-22s %llu\n", "voxels", (unsigned long long)co.voxels);
        printf("%-22s %.6f\n", "pearson r", co.pearson);
        printf("%-22s %.6f (channel %d's signal where channel %d's is)\n", "manders M1",
               co.manders_m1, r->coloc[0], r->coloc[1]);
        printf("%-22s %.6f (channel %d's signal where channel %d's is)\n", "manders M2",
               co.manders_m2, r->coloc[1], r->coloc[0]);
        printf("%-22s %g, %g (values above count as signal)\n", "thresholds", co.threshold[0],
               co.threshold[1]);
        printf("%-22s %g, %g\n", "means", co.mean[0], co.mean[1]);
    }
    vv_volume_free(v[0]);
    vv_volume_free(v[1]);
    vv_volume_free(mask);
    return rc;
}

/* --series, --channel, --time, --coloc, --mask, --thresholds. */
static int
parse_channel_options(cli_args *a, measure_req *r) {
    int rc;
    const char *s;
    if ((rc = cli_parse_series_channel(a, &r->series, &r->channel, &r->time)))
        return rc;
    r->coloc[0] = r->coloc[1] = -1;
    if ((s = cli_get(a, "coloc"))) {
        long c1, c2;
        char *e1, *e2;
        c1 = strtol(s, &e1, 10);
        if (e1 == s || *e1 != ',' || (c2 = strtol(e1 + 1, &e2, 10), e2 == e1 + 1) || *e2 ||
            c1 < 0 || c2 < 0 || c1 > 1000000 || c2 > 1000000 || c1 == c2)
            return cli_usage_error(a, "--coloc: '%s' is not two different channels C1,C2", s);
        r->coloc[0] = (int)c1;
        r->coloc[1] = (int)c2;
        if (r->channel >= 0)
            return cli_usage_error(a, "--coloc names its channels: not with --channel");
    }
    r->mask = cli_get(a, "mask");
    if ((s = cli_get(a, "thresholds"))) {
        char *e1, *e2;
        r->thresholds[0] = strtod(s, &e1);
        if (e1 == s || *e1 != ',' || (r->thresholds[1] = strtod(e1 + 1, &e2), e2 == e1 + 1) ||
            *e2 || !isfinite(r->thresholds[0]) || !isfinite(r->thresholds[1]))
            return cli_usage_error(a, "--thresholds: '%s' is not two values TA,TB", s);
    }
    if ((r->mask || cli_get(a, "thresholds")) && r->coloc[0] < 0)
        return cli_usage_error(a, "--mask and --thresholds go with --coloc C1,C2");
    return 0;
}

/* Measures INPUT as @p r says: a mesh, label volumes or a volume. */
static int
measure_input(cli_args *a, measure_req *r) {
    const char *in = a->pos[0];
    int rc;
    if (is_mesh_file(in) && !cli_get(a, "raw")) {
        if (r->has_iso || r->histogram || cli_get(a, "roi") || r->region.n_cut_planes ||
            cli_get(a, "method"))
            return cli_usage_error(a,
                                   "%s is a mesh: --iso, --seed, --method, --histogram, --roi "
                                   "and --cut measure volumes",
                                   in);
        if ((rc = cli_check_readable(in)))
            return rc;
        return measure_mesh(in, r);
    }
    if (r->to || r->want_volume)
        return cli_usage_error(a, "--to and --volume measure meshes (.ply .obj .stl .off)");
    vv_raw_params raw;
    const char *raw_spec = cli_get(a, "raw");
    if (cli_get(a, "memory-limit") && (cli_count(a, "labels") > 0 || r->coloc[0] >= 0))
        return cli_usage_error(a, "--memory-limit measures --iso and --histogram (not --labels "
                                  "or --coloc)");
    if (cli_count(a, "labels") > 0) {
        if (r->has_iso || r->histogram || r->has_distance)
            return cli_usage_error(a, "--labels measures the labels alone (not with --iso, "
                                      "--histogram or --distance)");
        if (raw_spec && (rc = cli_parse_raw(a, "raw", raw_spec, &raw)))
            return rc;
        return measure_labels(in, raw_spec ? &raw : NULL, r->json);
    }
    if (r->coloc[0] >= 0) {
        if (r->has_iso || r->histogram || r->has_distance)
            return cli_usage_error(a, "--coloc measures the two channels alone (not with --iso, "
                                      "--histogram or --distance)");
        if (raw_spec && (rc = cli_parse_raw(a, "raw", raw_spec, &raw)))
            return rc;
        if (r->mask && (rc = cli_check_readable_input(r->mask)))
            return rc;
        return measure_coloc(in, raw_spec ? &raw : NULL, r);
    }
    if (!r->has_iso && !r->histogram && !r->has_distance)
        return cli_usage_error(a, "nothing to measure: give --iso V, --histogram, --distance P1 "
                                  "P2 or --coloc C1,C2");
    const char *ml = cli_get(a, "memory-limit");
    if (ml && (rc = cli_parse_bytes(a, "memory-limit", ml, &r->memory_limit)))
        return rc;
    if (ml && (r->has_seed || cli_get(a, "roi") || r->region.n_cut_planes || r->has_geodesic ||
               cli_get(a, "series")))
        return cli_usage_error(a, "--memory-limit measures the whole volume box by box: not with "
                                  "--seed, --roi, --cut, --geodesic or --series");
    if (raw_spec && (rc = cli_parse_raw(a, "raw", raw_spec, &raw)))
        return rc;
    return measure_volume(in, raw_spec ? &raw : NULL, r);
}

int
cli_measure_main(int argc, char **argv) {
    char **av = NULL;
    char *joined[2] = {NULL, NULL};
    int ac = 0;
    int rc = join_point_args(argc, argv, &av, &ac, joined);
    if (rc) {
        free(joined[0]);
        free(joined[1]);
        return rc;
    }
    cli_args a;
    rc = cli_parse(&a, "measure", measure_opts, N_MEASURE_OPTS, ac, av);
    if (rc == CLI_HELP) {
        cli_measure_usage(stdout);
        rc = CLI_EXIT_OK;
        goto done;
    }
    if (rc)
        goto done;
    if (a.n_pos != 1) {
        rc = cli_usage_error(&a, a.n_pos ? "expected one INPUT, got %d arguments" : "missing INPUT",
                             a.n_pos);
        goto done;
    }
    measure_req r;
    memset(&r, 0, sizeof r);
    vv_roi_init(&r.region);
    r.bins = 32;
    r.method = VV_MEASURE_MC;
    r.json = cli_count(&a, "json") > 0;
    r.histogram = cli_count(&a, "histogram") > 0;
    r.log = cli_count(&a, "log") > 0;
    r.want_volume = cli_count(&a, "volume") > 0;
    r.plot = cli_get(&a, "plot");
    r.to = cli_get(&a, "to");
    if ((rc = parse_volume_options(&a, &r)) || (rc = parse_point_options(&a, &r)) ||
        (rc = parse_channel_options(&a, &r)))
        goto done;
    rc = measure_input(&a, &r);
done:
    free(joined[0]);
    free(joined[1]);
    free(av);
    return rc;
}
