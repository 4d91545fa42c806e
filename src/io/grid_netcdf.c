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

#include "io/grid_io_internal.h"
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

vv_status
vv_grid_read_netcdf(vv_grid **out, const char *path) {
    *out = NULL;
    int nc, e;
    if ((e = nc_open(path, NC_NOWRITE, &nc)) != NC_NOERR)
        return vv_error_set(e == NC_ENOTNC ? VV_ERR_FORMAT : VV_ERR_IO, "%s: %s", path,
                            nc_strerror(e));
    vv_status s = VV_OK;
    vv_grid *g = NULL;
    double *ax[3] = {NULL, NULL, NULL}, *edges[3] = {NULL, NULL, NULL}, *buf = NULL;
    int nvars = 0;
    if ((e = nc_inq_nvars(nc, &nvars)) != NC_NOERR) {
        s = nc_fail(e, path, "variables");
        goto done;
    }
    /* the first variable of 3 dimensions (or 4 with a leading one of length 1) */
    int dimids[NC_MAX_VAR_DIMS], ndims = 0, first = -1;
    for (int v = 0; v < nvars && first < 0; v++) {
        int nd;
        int ids[NC_MAX_VAR_DIMS];
        if (nc_inq_varndims(nc, v, &nd) != NC_NOERR || nc_inq_vardimid(nc, v, ids) != NC_NOERR)
            continue;
        size_t l0 = 0;
        if (nd == 4)
            nc_inq_dimlen(nc, ids[0], &l0);
        if (nd == 3 || (nd == 4 && l0 == 1)) {
            first = v;
            ndims = nd;
            memcpy(dimids, ids + (nd == 4), 3 * sizeof(int));
        }
    }
    if (first < 0) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: no variable of three dimensions", path);
        goto done;
    }
    char vname[NC_MAX_NAME + 1];
    nc_inq_varname(nc, first, vname);
    /* coordinate variables of the three dimensions: vertical, latitude, longitude */
    size_t len[3];
    int kind_of_dim[3], dim_of_kind[3] = {-1, -1, -1}, coord[3];
    for (int d = 0; d < 3; d++) {
        char dname[NC_MAX_NAME + 1];
        nc_inq_dim(nc, dimids[d], dname, &len[d]);
        if (nc_inq_varid(nc, dname, &coord[d]) != NC_NOERR) {
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: variable %s: dimension %s has no coordinate variable", path,
                             vname, dname);
            goto done;
        }
        kind_of_dim[d] = axis_kind(nc, coord[d], dname);
        if (kind_of_dim[d] < 0 || dim_of_kind[kind_of_dim[d]] >= 0) {
            s = vv_error_set(VV_ERR_UNSUPPORTED,
                             "%s: variable %s: dimension %s is not a longitude, latitude or "
                             "vertical axis (or repeats one)",
                             path, vname, dname);
            goto done;
        }
        dim_of_kind[kind_of_dim[d]] = d;
        if (len[d] < 1 || len[d] > 100000) {
            s = vv_error_set(VV_ERR_LIMIT, "%s: dimension %s of length %zu", path, dname, len[d]);
            goto done;
        }
        ax[d] = malloc(len[d] * sizeof(double));
        edges[d] = malloc((len[d] + 1) * sizeof(double));
        if (!ax[d] || !edges[d]) {
            s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
            goto done;
        }
        if ((e = nc_get_var_double(nc, coord[d], ax[d])) != NC_NOERR) {
            s = nc_fail(e, path, dname);
            goto done;
        }
        halfway_edges(ax[d], len[d], edges[d]);
        /* Ferret's "edges" or CF's "bounds" */
        char en[NC_MAX_NAME + 1];
        int ev;
        att_text(nc, coord[d], "edges", en, sizeof en);
        if (en[0] && nc_inq_varid(nc, en, &ev) == NC_NOERR) {
            int end_;
            size_t el = 0;
            int eid;
            if (nc_inq_varndims(nc, ev, &end_) == NC_NOERR && end_ == 1 &&
                nc_inq_vardimid(nc, ev, &eid) == NC_NOERR &&
                nc_inq_dimlen(nc, eid, &el) == NC_NOERR && el == len[d] + 1)
                nc_get_var_double(nc, ev, edges[d]);
        } else {
            att_text(nc, coord[d], "bounds", en, sizeof en);
            if (en[0] && nc_inq_varid(nc, en, &ev) == NC_NOERR) {
                double *b = malloc(2 * len[d] * sizeof *b);
                if (b && nc_get_var_double(nc, ev, b) == NC_NOERR) {
                    for (size_t i = 0; i < len[d]; i++)
                        edges[d][i] = b[2 * i];
                    edges[d][len[d]] = b[2 * len[d] - 1];
                }
                free(b);
            }
        }
    }
    for (int k = 0; k < 3; k++)
        if (dim_of_kind[k] < 0) {
            s = vv_error_set(VV_ERR_UNSUPPORTED, "%s: variable %s lacks a %s axis", path, vname,
                             k == 0   ? "longitude"
                             : k == 1 ? "latitude"
                                      : "vertical");
            goto done;
        }
    const int dlon = dim_of_kind[0], dlat = dim_of_kind[1], dz = dim_of_kind[2];
    const size_t nlon = len[dlon], nlat = len[dlat], nz = len[dz];
    /* vertical: depth (positive down, metres unless km) to radius */
    char units[64], positive[16];
    att_text(nc, coord[dz], "units", units, sizeof units);
    att_text(nc, coord[dz], "positive", positive, sizeof positive);
    const double to_km =
        !strncasecmp(units, "km", 2) || !strncasecmp(units, "kilomet", 7) ? 1.0 : 0.001;
    const int down = strcasecmp(positive, "up") != 0;
    double *r = malloc((nz + 1) * sizeof *r), *theta = malloc((nlat + 1) * sizeof *theta),
           *phi = malloc((nlon + 1) * sizeof *phi);
    if (!r || !theta || !phi) {
        free(r);
        free(theta);
        free(phi);
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
        goto done;
    }
    /* r increasing: the deepest edge first */
    const int zinc = edges[dz][nz] > edges[dz][0];
    for (size_t i = 0; i <= nz; i++) {
        const double zv = edges[dz][i] * to_km * (down ? -1 : 1); /* height, km */
        r[zinc == down ? nz - i : i] = VV_EARTH_RADIUS_KM + VV_NETCDF_EXAGGERATION * zv;
    }
    /* theta from +z (north) increasing: latitude decreasing */
    const int latinc = edges[dlat][nlat] > edges[dlat][0];
    for (size_t j = 0; j <= nlat; j++) {
        double lat = edges[dlat][latinc ? nlat - j : j];
        lat = lat > 90 ? 90 : lat < -90 ? -90 : lat;
        theta[j] = (90 - lat) * M_PI / 180;
    }
    const int loninc = edges[dlon][nlon] > edges[dlon][0];
    const double span = fabs(edges[dlon][nlon] - edges[dlon][0]);
    const int wrap = fabs(span - 360) < 1e-6 * 360;
    for (size_t k = 0; k <= nlon; k++)
        phi[k] = edges[dlon][loninc ? k : nlon - k] * M_PI / 180;
    s = vv_grid_new_spherical(&g, r, (int)nz + 1, theta, (int)nlat + 1, phi,
                              (int)nlon + (wrap ? 0 : 1), wrap);
    free(r);
    free(theta);
    free(phi);
    if (s != VV_OK) {
        s = vv_error_prefix(s, "%s", path);
        goto done;
    }
    /* every variable on the same dimensions: a cell field */
    const size_t ncell = nlon * nlat * nz;
    buf = malloc(ncell * sizeof *buf);
    if (!buf) {
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
        goto done;
    }
    for (int v = 0; v < nvars; v++) {
        int nd, ids[NC_MAX_VAR_DIMS];
        if (nc_inq_varndims(nc, v, &nd) != NC_NOERR || nd != ndims ||
            nc_inq_vardimid(nc, v, ids) != NC_NOERR ||
            memcmp(ids + (nd == 4), dimids, 3 * sizeof(int)))
            continue;
        char name[NC_MAX_NAME + 1];
        nc_inq_varname(nc, v, name);
        if ((e = nc_get_var_double(nc, v, buf)) != NC_NOERR) {
            s = nc_fail(e, path, name);
            goto done;
        }
        double fill = NAN, missing = NAN, scale = 1, offset = 0;
        int has_fill = nc_get_att_double(nc, v, "_FillValue", &fill) == NC_NOERR;
        int has_missing = nc_get_att_double(nc, v, "missing_value", &missing) == NC_NOERR;
        nc_get_att_double(nc, v, "scale_factor", &scale);
        nc_get_att_double(nc, v, "add_offset", &offset);
        vv_grid_field *f = NULL;
        if ((s = vv_grid_add_field(g, name, 1, 1, &f)) != VV_OK)
            goto done;
        f->has_fill = 1;
        f->fill = NAN; /* missing values are stored as NaN */
        size_t idx[3];
        for (size_t k = 0; k < nlon; k++)
            for (size_t j = 0; j < nlat; j++)
                for (size_t i = 0; i < nz; i++) {
                    /* grid cell (i: r, j: theta, k: phi) -> file indices */
                    idx[dz] = zinc == down ? nz - 1 - i : i;
                    idx[dlat] = latinc ? nlat - 1 - j : j;
                    idx[dlon] = loninc ? k : nlon - 1 - k;
                    const size_t src = (idx[0] * len[1] + idx[1]) * len[2] + idx[2];
                    double x = buf[src];
                    if ((has_fill && x == fill) || (has_missing && x == missing) || !isfinite(x))
                        x = NAN;
                    else
                        x = x * scale + offset;
                    f->values[(k * nlat + j) * nz + i] = (float)x;
                }
    }
done:
    nc_close(nc);
    free(buf);
    for (int d = 0; d < 3; d++) {
        free(ax[d]);
        free(edges[d]);
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

const vv_grid_format_record vv_grid_format_netcdf = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "netcdf",
    .title = "NetCDF",
    .extensions = netcdf_extensions,
    .doc = "NetCDF (CF conventions) through libnetcdf: cells on longitude, latitude, depth",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = netcdf_looks_like,
    .read = vv_grid_read_netcdf,
};
