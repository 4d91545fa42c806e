/*
 * NetCDF files following the CF conventions (and Ferret's older ones) as
 * spherical grids, through libnetcdf: the variables on (vertical,
 * latitude, longitude) become cell fields of a spherical grid whose points
 * are the cell edges: longitude edges halfway between the coordinate
 * values (a full circle of longitudes wraps), latitude edges likewise
 * (clamped to the poles), vertical edges from the axis's "edges" (Ferret)
 * or "bounds" (CF) variable, else halfway. Data is kept as cell data, as
 * the model wrote it; _FillValue and missing_value become the field's fill
 * value (transparent), scale_factor and add_offset are applied.
 *
 * Radius: world units are kilometres, r = 6371 - VV_NETCDF_EXAGGERATION x
 * depth (depth in km; positive up axes are heights), so that the ocean's
 * 5 km are visible on the globe: the depth is exaggerated 500 times.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/grid/grid_io_internal.h"
#include "io/io_internal.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

#ifdef VV_HAVE_NETCDF
#include <netcdf.h>

#define VV_NETCDF_EXAGGERATION 500.0
#define VV_EARTH_RADIUS_KM 6371.0

static vv_status
nc_fail(int e, const char *path, const char *what) {
    return vv_error_set(VV_ERR_FORMAT, "%s: %s: %s", path, what, nc_strerror(e));
}

static void
att_text(int nc, int var, const char *name, char *buf, size_t cap) {
    size_t len = 0;
    buf[0] = '\0';
    nc_type t;
    if (nc_inq_att(nc, var, name, &t, &len) != NC_NOERR || t != NC_CHAR || len + 1 > cap)
        return;
    if (nc_get_att_text(nc, var, name, buf) == NC_NOERR)
        buf[len] = '\0';
}

/* 0 longitude, 1 latitude, 2 vertical, -1 unknown */
static int
axis_kind(int nc, int var, const char *name) {
    char units[64], axis[16], positive[16];
    att_text(nc, var, "units", units, sizeof units);
    att_text(nc, var, "axis", axis, sizeof axis);
    att_text(nc, var, "positive", positive, sizeof positive);
    if (!strncasecmp(units, "degrees_east", 12) || !strncasecmp(units, "degree_east", 11) ||
        !strcasecmp(axis, "X") || !strncasecmp(name, "lon", 3))
        return 0;
    if (!strncasecmp(units, "degrees_north", 13) || !strncasecmp(units, "degree_north", 12) ||
        !strcasecmp(axis, "Y") || !strncasecmp(name, "lat", 3))
        return 1;
    if (positive[0] || !strcasecmp(axis, "Z") || !strncasecmp(name, "depth", 5) ||
        !strncasecmp(name, "lev", 3))
        return 2;
    return -1;
}

/* Edges of a coordinate axis of n centres: n + 1 values, halfway between. */
static void
halfway_edges(const double *c, size_t n, double *e) {
    for (size_t i = 1; i < n; i++)
        e[i] = 0.5 * (c[i - 1] + c[i]);
    e[0] = n > 1 ? c[0] - (e[1] - c[0]) : c[0] - 0.5;
    e[n] = n > 1 ? c[n - 1] + (c[n - 1] - e[n - 1]) : c[0] + 0.5;
}

/* What the reader found of a file: its first three-dimensional variable
 * (the layout every field shares) and the three coordinate axes. */
typedef struct nc_layout {
    int nc;
    const char *path;
    int nvars, ndims, dimids[3];
    char vname[NC_MAX_NAME + 1];
    size_t len[3];                  /* per dimension of the variable */
    int coord[3];                   /* the dimension's coordinate variable */
    int dim_of_kind[3];             /* dimension of longitude, latitude, vertical */
    double *ax[3], *edges[3];       /* centres (len) and edges (len + 1) per dimension */
    int zinc, down, latinc, loninc; /* the directions of the axes in the file */
} nc_layout;

/* The first variable of 3 dimensions (or 4 with a leading one of length 1). */
static vv_status
nc_first_variable(nc_layout *L) {
    int e, first = -1;
    if ((e = nc_inq_nvars(L->nc, &L->nvars)) != NC_NOERR)
        return nc_fail(e, L->path, "variables");
    for (int v = 0; v < L->nvars && first < 0; v++) {
        int nd;
        int ids[NC_MAX_VAR_DIMS];
        if (nc_inq_varndims(L->nc, v, &nd) != NC_NOERR ||
            nc_inq_vardimid(L->nc, v, ids) != NC_NOERR)
            continue;
        size_t l0 = 0;
        if (nd == 4)
            nc_inq_dimlen(L->nc, ids[0], &l0);
        if (nd == 3 || (nd == 4 && l0 == 1)) {
            first = v;
            L->ndims = nd;
            memcpy(L->dimids, ids + (nd == 4), 3 * sizeof(int));
        }
    }
    if (first < 0)
        return vv_error_set(VV_ERR_FORMAT, "%s: no variable of three dimensions", L->path);
    nc_inq_varname(L->nc, first, L->vname);
    return VV_OK;
}

/* The edges of axis @p d from Ferret's "edges" or CF's "bounds" variable,
 * when the coordinate variable names one (else they stay halfway). */
static void
nc_axis_edges(const nc_layout *L, int d) {
    char en[NC_MAX_NAME + 1];
    int ev;
    const int nc = L->nc, cv = L->coord[d];
    const size_t n = L->len[d];
    att_text(nc, cv, "edges", en, sizeof en);
    if (en[0] && nc_inq_varid(nc, en, &ev) == NC_NOERR) {
        int end_;
        size_t el = 0;
        int eid;
        if (nc_inq_varndims(nc, ev, &end_) == NC_NOERR && end_ == 1 &&
            nc_inq_vardimid(nc, ev, &eid) == NC_NOERR && nc_inq_dimlen(nc, eid, &el) == NC_NOERR &&
            el == n + 1)
            nc_get_var_double(nc, ev, L->edges[d]);
        return;
    }
    att_text(nc, cv, "bounds", en, sizeof en);
    if (en[0] && nc_inq_varid(nc, en, &ev) == NC_NOERR) {
        double *b = malloc(2 * n * sizeof *b);
        if (b && nc_get_var_double(nc, ev, b) == NC_NOERR) {
            for (size_t i = 0; i < n; i++)
                L->edges[d][i] = b[2 * i];
            L->edges[d][n] = b[2 * n - 1];
        }
        free(b);
    }
}

/* Dimension @p d: its coordinate variable, which axis it is, its centres
 * and edges. */
static vv_status
nc_axis(nc_layout *L, int d) {
    char dname[NC_MAX_NAME + 1];
    int e;
    nc_inq_dim(L->nc, L->dimids[d], dname, &L->len[d]);
    if (nc_inq_varid(L->nc, dname, &L->coord[d]) != NC_NOERR)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: variable %s: dimension %s has no coordinate variable", L->path,
                            L->vname, dname);
    const int kind = axis_kind(L->nc, L->coord[d], dname);
    if (kind < 0 || L->dim_of_kind[kind] >= 0)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "%s: variable %s: dimension %s is not a longitude, latitude or "
                            "vertical axis (or repeats one)",
                            L->path, L->vname, dname);
    L->dim_of_kind[kind] = d;
    if (L->len[d] < 1 || L->len[d] > 100000)
        return vv_error_set(VV_ERR_LIMIT, "%s: dimension %s of length %zu", L->path, dname,
                            L->len[d]);
    L->ax[d] = malloc(L->len[d] * sizeof(double));
    L->edges[d] = malloc((L->len[d] + 1) * sizeof(double));
    if (!L->ax[d] || !L->edges[d])
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", L->path);
    if ((e = nc_get_var_double(L->nc, L->coord[d], L->ax[d])) != NC_NOERR)
        return nc_fail(e, L->path, dname);
    halfway_edges(L->ax[d], L->len[d], L->edges[d]);
    nc_axis_edges(L, d);
    return VV_OK;
}

/* The spherical grid of the axes' edges: radius from the vertical axis
 * (depth positive down, metres unless km, exaggerated), theta from the
 * latitude, phi from the longitude (wrapping round a whole turn). */
static vv_status
nc_spherical(nc_layout *L, vv_grid **g) {
    const int dlon = L->dim_of_kind[0], dlat = L->dim_of_kind[1], dz = L->dim_of_kind[2];
    const size_t nlon = L->len[dlon], nlat = L->len[dlat], nz = L->len[dz];
    const double *ez = L->edges[dz], *elat = L->edges[dlat], *elon = L->edges[dlon];
    char units[64], positive[16];
    att_text(L->nc, L->coord[dz], "units", units, sizeof units);
    att_text(L->nc, L->coord[dz], "positive", positive, sizeof positive);
    const double to_km =
        !strncasecmp(units, "km", 2) || !strncasecmp(units, "kilomet", 7) ? 1.0 : 0.001;
    L->down = strcasecmp(positive, "up") != 0;
    double *r = malloc((nz + 1) * sizeof *r), *theta = malloc((nlat + 1) * sizeof *theta),
           *phi = malloc((nlon + 1) * sizeof *phi);
    vv_status s = VV_OK;
    if (!r || !theta || !phi) {
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", L->path);
        goto done;
    }
    /* r increasing: the deepest edge first */
    L->zinc = ez[nz] > ez[0];
    for (size_t i = 0; i <= nz; i++) {
        const double zv = ez[i] * to_km * (L->down ? -1 : 1); /* height, km */
        r[L->zinc == L->down ? nz - i : i] = VV_EARTH_RADIUS_KM + VV_NETCDF_EXAGGERATION * zv;
    }
    /* theta from +z (north) increasing: latitude decreasing */
    L->latinc = elat[nlat] > elat[0];
    for (size_t j = 0; j <= nlat; j++) {
        double lat = elat[L->latinc ? nlat - j : j];
        lat = lat > 90 ? 90 : lat < -90 ? -90 : lat;
        theta[j] = (90 - lat) * M_PI / 180;
    }
    L->loninc = elon[nlon] > elon[0];
    const double span = fabs(elon[nlon] - elon[0]);
    const int wrap = fabs(span - 360) < 1e-6 * 360;
    for (size_t k = 0; k <= nlon; k++)
        phi[k] = elon[L->loninc ? k : nlon - k] * M_PI / 180;
    s = vv_grid_new_spherical(g, r, (int)nz + 1, theta, (int)nlat + 1, phi,
                              (int)nlon + (wrap ? 0 : 1), wrap);
    if (s != VV_OK)
        s = vv_error_prefix(s, "%s", L->path);
done:
    free(r);
    free(theta);
    free(phi);
    return s;
}

/* Variable @p v as a cell field: fill and missing values as NaN, scale
 * and offset applied, reordered from the file's axes to the grid's. */
static vv_status
nc_field(const nc_layout *L, int v, double *buf, vv_grid *g) {
    const int dlon = L->dim_of_kind[0], dlat = L->dim_of_kind[1], dz = L->dim_of_kind[2];
    const size_t nlon = L->len[dlon], nlat = L->len[dlat], nz = L->len[dz];
    char name[NC_MAX_NAME + 1];
    int e;
    nc_inq_varname(L->nc, v, name);
    if ((e = nc_get_var_double(L->nc, v, buf)) != NC_NOERR)
        return nc_fail(e, L->path, name);
    double fill = NAN, missing = NAN, scale = 1, offset = 0;
    int has_fill = nc_get_att_double(L->nc, v, "_FillValue", &fill) == NC_NOERR;
    int has_missing = nc_get_att_double(L->nc, v, "missing_value", &missing) == NC_NOERR;
    nc_get_att_double(L->nc, v, "scale_factor", &scale);
    nc_get_att_double(L->nc, v, "add_offset", &offset);
    vv_grid_field *f = NULL;
    vv_status s = vv_grid_add_field(g, name, 1, 1, &f);
    if (s != VV_OK)
        return s;
    f->has_fill = 1;
    f->fill = NAN; /* missing values are stored as NaN */
    size_t idx[3];
    for (size_t k = 0; k < nlon; k++)
        for (size_t j = 0; j < nlat; j++)
            for (size_t i = 0; i < nz; i++) {
                /* grid cell (i: r, j: theta, k: phi) -> file indices */
                idx[dz] = L->zinc == L->down ? nz - 1 - i : i;
                idx[dlat] = L->latinc ? nlat - 1 - j : j;
                idx[dlon] = L->loninc ? k : nlon - 1 - k;
                const size_t src = (idx[0] * L->len[1] + idx[1]) * L->len[2] + idx[2];
                double x = buf[src];
                if ((has_fill && x == fill) || (has_missing && x == missing) || !isfinite(x))
                    x = NAN;
                else
                    x = x * scale + offset;
                f->values[(k * nlat + j) * nz + i] = (float)x;
            }
    return VV_OK;
}

/* Every variable on the first variable's dimensions, as a cell field. */
static vv_status
nc_fields(const nc_layout *L, vv_grid *g) {
    const size_t ncell = L->len[0] * L->len[1] * L->len[2];
    double *buf = malloc(ncell * sizeof *buf);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", L->path);
    vv_status s = VV_OK;
    for (int v = 0; v < L->nvars && s == VV_OK; v++) {
        int nd, ids[NC_MAX_VAR_DIMS];
        if (nc_inq_varndims(L->nc, v, &nd) != NC_NOERR || nd != L->ndims ||
            nc_inq_vardimid(L->nc, v, ids) != NC_NOERR ||
            memcmp(ids + (nd == 4), L->dimids, 3 * sizeof(int)))
            continue;
        s = nc_field(L, v, buf, g);
    }
    free(buf);
    return s;
}

vv_status
vv_grid_read_netcdf(vv_grid **out, const char *path) {
    *out = NULL;
    nc_layout L;
    memset(&L, 0, sizeof L);
    L.path = path;
    L.dim_of_kind[0] = L.dim_of_kind[1] = L.dim_of_kind[2] = -1;
    int e;
    if ((e = nc_open(path, NC_NOWRITE, &L.nc)) != NC_NOERR)
        return vv_error_set(e == NC_ENOTNC ? VV_ERR_FORMAT : VV_ERR_IO, "%s: %s", path,
                            nc_strerror(e));
    vv_grid *g = NULL;
    vv_status s = nc_first_variable(&L);
    for (int d = 0; d < 3 && s == VV_OK; d++)
        s = nc_axis(&L, d);
    for (int k = 0; k < 3 && s == VV_OK; k++)
        if (L.dim_of_kind[k] < 0)
            s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: variable %s lacks a %s axis", path, L.vname,
                             k == 0   ? "longitude"
                             : k == 1 ? "latitude"
                                      : "vertical");
    if (s == VV_OK && (s = nc_spherical(&L, &g)) == VV_OK)
        s = nc_fields(&L, g);
    nc_close(L.nc);
    for (int d = 0; d < 3; d++) {
        free(L.ax[d]);
        free(L.edges[d]);
    }
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    return vv_grid_finish(g, path, out);
}

#else

vv_status
vv_grid_read_netcdf(vv_grid **out, const char *path) {
    *out = NULL;
    return vv_error_set(VV_ERR_UNSUPPORTED, "%s: this build has no NetCDF (libnetcdf-dev)", path);
}

#endif

/* ---- the format record ------------------------------------------------------ */

/* NetCDF classic ("CDF" and version 1, 2 or 5), or NetCDF-4 (an HDF5 file)
 * named .nc or .cdf. */
static int
netcdf_looks_like(const vv_format_probe *p, int deep) {
    const unsigned char *h = p->head;
    if (deep || p->n < 4)
        return 0;
    if (!memcmp(h, "CDF", 3) && (h[3] == 1 || h[3] == 2 || h[3] == 5))
        return 1;
    return p->n >= 8 && !memcmp(h, "\x89HDF\r\n\x1a\n", 8) &&
           (vv_format_path_has_ext(p->path, "nc") || vv_format_path_has_ext(p->path, "cdf"));
}

static const char *const netcdf_extensions[] = {"nc", "cdf", NULL};

const vv_format_record vv_format_netcdf = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "netcdf",
    .title = "NetCDF",
    .extensions = netcdf_extensions,
    .doc = "NetCDF (CF conventions) through libnetcdf: cells on longitude, latitude, depth",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .holds = VV_DATA_GRID,
    .looks_like = netcdf_looks_like,
    .read_grid = vv_grid_read_netcdf,
};
