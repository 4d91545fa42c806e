/*
 * volvis isosurface INPUT --iso V -o OUT.(ply|obj|stl|glb|vtp) [--coarse L | --parc L]:
 * Marching Cubes surface (or one of the Navigator's previews) to a mesh file.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec iso_opts[] = {
    {"iso", 0, "V"},
    {"output", 'o', "OUT"},
    {"coarse", 0, "L"},
    {"parc", 0, "L"},
    {"roi", 0, "I0,J0,K0:I1,J1,K1"},
    {"cut", 0, "PX,PY,PZ:NX,NY,NZ"},
    {"no-normals", 0, NULL},
    {"threads", 0, "N"},
    {"raw", 0, "WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]"},
    {"field", 0, "NAME"},
    {"quiet", 'q', NULL},
};
#define N_ISO_OPTS ((int)(sizeof iso_opts / sizeof iso_opts[0]))

/* Marching Tetrahedra of a grid file's field (its first scalar field by default). */
static int
isosurface_grid(const char *in, const char *out, double iso, const char *field, int normals,
                int quiet) {
    vv_grid *g = NULL;
    vv_error_clear();
    vv_status st = vv_grid_load(&g, in);
    if (st != VV_OK)
        return cli_fail(st, NULL);
    int f = -1;
    for (int i = 0; i < g->n_fields && f < 0; i++)
        if (field ? !strcmp(g->fields[i].name, field) : g->fields[i].n_components == 1)
            f = i;
    if (f < 0) {
        cli_error("%s: no field %s", in, field ? field : "of one component");
        vv_grid_free(g);
        return CLI_EXIT_FAIL;
    }
    vv_mesh *m = NULL;
    st = vv_grid_isosurface(g, f, -1, iso, &m);
    if (st == VV_OK && m->n_triangles == 0) {
        cli_error("%s: no triangles at isovalue %g of field %s (range %g .. %g)", in, iso,
                  g->fields[f].name, g->fields[f].range[0], g->fields[f].range[1]);
        vv_mesh_free(m);
        vv_grid_free(g);
        return CLI_EXIT_FAIL;
    }
    if (st == VV_OK && !normals && m->normals) {
        free(m->normals);
        m->normals = NULL;
    }
    if (st == VV_OK)
        st = vv_mesh_save(m, out);
    if (st != VV_OK) {
        int rc = cli_fail(st, st == VV_ERR_IO ? out : in);
        vv_mesh_free(m);
        vv_grid_free(g);
        return rc;
    }
    if (!quiet)
        printf("wrote %s (Marching Tetrahedra of %s at %g: %zu vertices, %zu triangles, area "
               "%.6g units^2)\n",
               out, g->fields[f].name, iso, m->n_vertices, m->n_triangles, vv_mesh_area(m));
    vv_mesh_free(m);
    vv_grid_free(g);
    return CLI_EXIT_OK;
}

void
cli_isosurface_usage(FILE *out) {
    fprintf(
        out,
        "usage: volvis isosurface [OPTIONS] INPUT --iso V -o OUT.(ply|obj|stl|glb|vtp)\n"
        "\n"
        "Extracts the isosurface value == V of a volume with Marching Cubes (asymptotic\n"
        "decider on ambiguous faces: closed, crack-free surfaces) in world coordinates,\n"
        "with normals from the volume gradient, and writes it as binary PLY, OBJ,\n"
        "binary STL, glTF 2.0 binary (.glb) or VTK XML PolyData (.vtp, normals as a\n"
        "point field) (from OUT's extension). Triangles face the lower values (for CT\n"
        "bone at 300: out of the bone). Or writes one of the Navigator's previews:\n"
        "  --coarse L   coarse Marching Cubes on a grid reduced 2^L times, each vertex\n"
        "               at one of 4 positions along its edge (L = 0..8)\n"
        "  --parc L     the outer faces of the PARC subvolumes (boxes) that hold part of\n"
        "               the surface; the longest axis is split into 2^L boxes (L = 0..16)\n"
        "Prints what was written (vertices, triangles, area in world units).\n"
        "INPUT may be an irregular grid (VTK UNSTRUCTURED_GRID, .vtu, OpenDX, PLOT3D,\n"
        "NetCDF): its field (--field NAME, default the first scalar field) is\n"
        "triangulated by Marching Tetrahedra over its cells.\n"
        "\n"
        "Options:\n"
        "  --iso V        the isovalue; voxels >= V are inside (required; must lie in\n"
        "                 the volume's value range)\n"
        "  -o, --output OUT  the mesh file: .ply, .obj, .stl, .glb or .vtp (required)\n"
        "  --roi I0,J0,K0:I1,J1,K1   only this voxel box (inclusive; Marching Cubes)\n"
        "  --cut PX,PY,PZ:NX,NY,NZ   clip to the side of the plane the normal points to\n"
        "                 (world coordinates; repeatable, up to 8; Marching Cubes)\n"
        "  --no-normals   write no normals\n"
        "  --field NAME   a grid's field (grids only)\n"
        "  --threads N    threads (default: all cores)\n"
        "  --raw WxHxD:TYPE[:be|le][:SXxSYxSZ][:skip=N]\n"
        "                 read INPUT as raw voxels (see 'volvis info --help')\n"
        "  -q, --quiet    no 'wrote' line\n"
        "  -h, --help     show this help\n"
        "\n"
        "Examples:\n"
        "  volvis isosurface ../shared/data/volumes/ct_head.nrrd --iso 300 -o bone.ply\n"
        "  volvis isosurface ../shared/data/volumes/ct_head.nrrd --iso 300 --coarse 2 -o "
        "preview.stl\n"
        "  volvis isosurface ../shared/data/volumes/neghip.slc --iso 60 --parc 4 -o boxes.obj\n");
}

int
cli_isosurface_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "isosurface", iso_opts, N_ISO_OPTS, argc, argv);
    if (rc == CLI_HELP) {
        cli_isosurface_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos != 1)
        return cli_usage_error(
            &a, a.n_pos ? "expected one INPUT, got %d arguments" : "missing INPUT", a.n_pos);
    const char *in = a.pos[0], *out = cli_get(&a, "output"), *s;
    if (!out)
        return cli_usage_error(&a, "missing -o OUT.(ply|obj|stl|glb|vtp)");
    size_t n = strlen(out);
    int known = 0;
    for (const char *const *e = (const char *const[]){".ply", ".obj", ".stl", ".glb", ".vtp", NULL};
         *e; e++)
        known |= n > 4 && !strcmp(out + n - 4, *e);
    if (!known)
        return cli_usage_error(&a, "-o: '%s' does not end in .ply, .obj, .stl, .glb or .vtp", out);
    double iso;
    if (!(s = cli_get(&a, "iso")))
        return cli_usage_error(&a, "missing --iso V");
    if ((rc = cli_parse_double(&a, "iso", s, -HUGE_VAL, HUGE_VAL, &iso)))
        return rc;
    int coarse = -1, parc = -1, threads = 0;
    if ((s = cli_get(&a, "coarse")) && (rc = cli_parse_int(&a, "coarse", s, 0, 8, &coarse)))
        return rc;
    if ((s = cli_get(&a, "parc")) && (rc = cli_parse_int(&a, "parc", s, 0, 16, &parc)))
        return rc;
    if (coarse >= 0 && parc >= 0)
        return cli_usage_error(&a, "--coarse and --parc exclude each other");
    if ((s = cli_get(&a, "threads")) && (rc = cli_parse_int(&a, "threads", s, 0, 4096, &threads)))
        return rc;
    vv_isosurface_options o;
    vv_isosurface_options_init(&o);
    o.threads = threads;
    o.compute_normals = cli_count(&a, "no-normals") == 0;
    if ((s = cli_get(&a, "roi")) && (rc = cli_parse_roi(&a, "roi", s, o.roi_min, o.roi_max)))
        return rc;
    for (int i = 0; i < a.n_seen; i++) {
        if (strcmp(a.specs[a.seen[i].opt].name, "cut"))
            continue;
        if (o.n_cut_planes == VV_MAX_CUT_PLANES)
            return cli_usage_error(&a, "--cut: at most %d planes", VV_MAX_CUT_PLANES);
        if ((rc = cli_parse_plane(&a, "cut", a.seen[i].value, &o.cut_planes[o.n_cut_planes++])))
            return rc;
    }
    if ((coarse >= 0 || parc >= 0) && (o.roi_max[0] >= 0 || o.n_cut_planes))
        return cli_usage_error(&a, "--roi and --cut apply to the full Marching Cubes surface only");
    int quiet = cli_count(&a, "quiet") > 0;
    vv_raw_params raw;
    const char *raw_spec = cli_get(&a, "raw");
    if (raw_spec && (rc = cli_parse_raw(&a, "raw", raw_spec, &raw)))
        return rc;
    if (!raw_spec && vv_grid_file_detect(in, NULL)) {
        /* an irregular grid: Marching Tetrahedra of its field */
        if (coarse >= 0 || parc >= 0 || o.roi_max[0] >= 0 || o.n_cut_planes)
            return cli_usage_error(&a, "--coarse, --parc, --roi and --cut apply to volumes only");
        return isosurface_grid(in, out, iso, cli_get(&a, "field"), o.compute_normals, quiet);
    }
    vv_volume *v;
    if ((rc = cli_load_volume(in, raw_spec ? &raw : NULL, &v)))
        return rc;
    if (!(iso > v->range[0] && iso <= v->range[1])) {
        cli_error("%s: isovalue %g is outside the volume's value range (%g, %g]: the surface is "
                  "empty",
                  in, iso, v->range[0], v->range[1]);
        vv_volume_free(v);
        return CLI_EXIT_FAIL;
    }
    if (o.roi_max[0] >= 0)
        for (int ax = 0; ax < 3; ax++)
            if (o.roi_min[ax] > o.roi_max[ax] || o.roi_max[ax] >= v->dims[ax]) {
                vv_volume_free(v);
                return cli_usage_error(&a, "--roi: %d..%d on axis %c is empty or outside 0..%d",
                                       o.roi_min[ax], o.roi_max[ax], "ijk"[ax], v -> dims[ax] - 1);
            }
    cli_progress pr;
    cli_progress_begin(&pr, quiet);
    o.progress = pr.p;
    vv_mesh *m = NULL;
    vv_status st = VV_OK;
    const char *what = "Marching Cubes";
    if (coarse >= 0) {
        vv_coarse_surface *c = NULL;
        what = "coarse Marching Cubes";
        if ((st = vv_coarse_new(&c, v, coarse)) == VV_OK &&
            (st = vv_coarse_set_isovalue(c, iso, threads)) == VV_OK)
            st = vv_coarse_mesh(c, &m);
        vv_coarse_free(c);
    } else if (parc >= 0) {
        vv_parc *p = NULL;
        what = "PARC subvolumes";
        if ((st = vv_parc_new(&p, v, parc)) == VV_OK &&
            (st = vv_parc_set_isovalue(p, iso)) == VV_OK)
            st = vv_parc_mesh(p, &m);
        vv_parc_free(p);
    } else {
        st = vv_isosurface_extract(&m, v, iso, &o);
    }
    cli_progress_end(&pr);
    if (st == VV_OK && m->n_triangles == 0) {
        cli_error("%s: no triangles at isovalue %g (the region holds no surface)", in, iso);
        vv_mesh_free(m);
        vv_volume_free(v);
        return CLI_EXIT_FAIL;
    }
    if (st == VV_OK && !o.compute_normals && m->normals) {
        free(m->normals);
        m->normals = NULL;
    }
    if (st == VV_OK)
        st = vv_mesh_save(m, out);
    if (st != VV_OK) {
        rc = cli_fail(st, st == VV_ERR_IO ? out : in);
        vv_mesh_free(m);
        vv_volume_free(v);
        return rc;
    }
    if (!quiet)
        printf("wrote %s (%s at %g: %zu vertices, %zu triangles, area %.6g %s^2)\n", out, what, iso,
               m->n_vertices, m->n_triangles, vv_mesh_area(m),
               v->unit == VV_UNIT_UNKNOWN ? "units" : vv_unit_name(v->unit));
    vv_mesh_free(m);
    vv_volume_free(v);
    return CLI_EXIT_OK;
}
