/*
 * The CLI's option parser and number parsing. Numbers are read with
 * strtod/strtol and an end-pointer check, so "5x", "", "1e999", "nan" and
 * "inf" are all refused with a one-line usage error.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int
find_long(const cli_opt_spec *specs, int n, const char *name, size_t len) {
    for (int i = 0; i < n; i++)
        if (strlen(specs[i].name) == len && strncmp(specs[i].name, name, len) == 0)
            return i;
    return -1;
}

static int
find_short(const cli_opt_spec *specs, int n, char c) {
    for (int i = 0; i < n; i++)
        if (specs[i].short_name == c)
            return i;
    return -1;
}

static int
add_seen(cli_args *a, int opt, const char *value) {
    if (a->n_seen >= CLI_MAX_ARGS)
        return cli_usage_error(a, "too many options (at most %d)", CLI_MAX_ARGS);
    a->seen[a->n_seen].opt = opt;
    a->seen[a->n_seen].value = value;
    a->n_seen++;
    return 0;
}

int
cli_parse(cli_args *a, const char *cmd, const cli_opt_spec *specs, int n_specs, int argc,
          char **argv) {
    memset(a, 0, sizeof *a);
    a->cmd = cmd;
    a->specs = specs;
    a->n_specs = n_specs;

    /* --help wins over every other problem on the line. */
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--") == 0)
            break;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return CLI_HELP;
    }

    int only_positional = 0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (only_positional || arg[0] != '-' || arg[1] == '\0') {
            if (a->n_pos >= CLI_MAX_ARGS)
                return cli_usage_error(a, "too many arguments (at most %d)", CLI_MAX_ARGS);
            a->pos[a->n_pos++] = arg;
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            only_positional = 1;
            continue;
        }
        int opt;
        const char *value = NULL;
        const char *shown = arg;
        if (arg[1] == '-') {
            const char *name = arg + 2;
            const char *eq = strchr(name, '=');
            size_t len = eq ? (size_t)(eq - name) : strlen(name);
            opt = find_long(specs, n_specs, name, len);
            if (opt < 0)
                return cli_usage_error(a, "unknown option '--%.*s'", (int)len, name);
            if (eq) {
                if (!specs[opt].metavar)
                    return cli_usage_error(a, "option '--%s' takes no value", specs[opt].name);
                value = eq + 1;
            }
        } else {
            opt = find_short(specs, n_specs, arg[1]);
            if (opt < 0)
                return cli_usage_error(a, "unknown option '-%c'", arg[1]);
            if (arg[2] != '\0') {
                if (!specs[opt].metavar)
                    return cli_usage_error(a, "option '-%c' takes no value", arg[1]);
                value = arg + 2;
            }
        }
        if (specs[opt].metavar && !value) {
            if (i + 1 >= argc)
                return cli_usage_error(a, "option '%s' needs a value (%s)", shown,
                                       specs[opt].metavar);
            value = argv[++i];
        }
        int rc = add_seen(a, opt, value);
        if (rc)
            return rc;
    }
    return 0;
}

static int
spec_index(const cli_args *a, const char *name) {
    return find_long(a->specs, a->n_specs, name, strlen(name));
}

const char *
cli_get(const cli_args *a, const char *name) {
    int opt = spec_index(a, name);
    const char *v = NULL;
    for (int i = 0; i < a->n_seen; i++)
        if (a->seen[i].opt == opt)
            v = a->seen[i].value ? a->seen[i].value : "";
    return v;
}

int
cli_count(const cli_args *a, const char *name) {
    int opt = spec_index(a, name);
    int n = 0;
    for (int i = 0; i < a->n_seen; i++)
        n += a->seen[i].opt == opt;
    return n;
}

/* ---- numbers ------------------------------------------------------------- */

/* Reads a finite double from the start of s; *end points past it. 0 on failure. */
static int
scan_double(const char *s, const char **end, double *out) {
    if (!*s || isspace((unsigned char)*s))
        return 0;
    char *e;
    errno = 0;
    double v = strtod(s, &e);
    if (e == s || errno == ERANGE || !isfinite(v))
        return 0;
    *end = e;
    *out = v;
    return 1;
}

static int
scan_long(const char *s, const char **end, long *out) {
    if (!*s || isspace((unsigned char)*s))
        return 0;
    char *e;
    errno = 0;
    long v = strtol(s, &e, 10);
    if (e == s || errno == ERANGE)
        return 0;
    *end = e;
    *out = v;
    return 1;
}

int
cli_parse_double(const cli_args *a, const char *opt, const char *text, double lo, double hi,
                 double *out) {
    const char *end;
    double v;
    if (!scan_double(text, &end, &v) || *end != '\0')
        return cli_usage_error(a, "--%s: expected a finite number, got '%s'", opt, text);
    if (v < lo || v > hi)
        return cli_usage_error(a, "--%s: %s is out of range [%g, %g]", opt, text, lo, hi);
    *out = v;
    return 0;
}

int
cli_parse_int(const cli_args *a, const char *opt, const char *text, long lo, long hi, int *out) {
    const char *end;
    long v;
    if (!scan_long(text, &end, &v) || *end != '\0')
        return cli_usage_error(a, "--%s: expected an integer, got '%s'", opt, text);
    if (v < lo || v > hi)
        return cli_usage_error(a, "--%s: %s is out of range [%ld, %ld]", opt, text, lo, hi);
    *out = (int)v;
    return 0;
}

int
cli_parse_bytes(const cli_args *a, const char *opt, const char *text, uint64_t *out) {
    char *end = NULL;
    const double x = strtod(text, &end);
    double mul = 1;
    if (end && (*end == 'K' || *end == 'k'))
        mul = 1024.0, end++;
    else if (end && (*end == 'M' || *end == 'm'))
        mul = 1048576.0, end++;
    else if (end && (*end == 'G' || *end == 'g'))
        mul = 1073741824.0, end++;
    if (!end || end == text || *end || !(x > 0) || x * mul > 1e18)
        return cli_usage_error(a, "--%s: '%s' is not a size (e.g. 512M, 1G)", opt, text);
    *out = (uint64_t)(x * mul);
    return 0;
}

int
cli_parse_size(const cli_args *a, const char *opt, const char *text, int *w, int *h) {
    const char *p = text, *end;
    long v[2];
    for (int i = 0; i < 2; i++) {
        if (!isdigit((unsigned char)*p) || !scan_long(p, &end, &v[i]))
            goto bad;
        p = end;
        if (i == 0) {
            if (*p != 'x' && *p != 'X')
                goto bad;
            p++;
        }
    }
    if (*p != '\0')
        goto bad;
    if (v[0] < 1 || v[0] > VV_IMAGE_MAX_SIDE || v[1] < 1 || v[1] > VV_IMAGE_MAX_SIDE)
        return cli_usage_error(a, "--%s: sides must be 1..%d, got '%s'", opt, VV_IMAGE_MAX_SIDE,
                               text);
    *w = (int)v[0];
    *h = (int)v[1];
    return 0;
bad:
    return cli_usage_error(a, "--%s: expected WIDTHxHEIGHT such as 512x512, got '%s'", opt, text);
}

int
cli_parse_range(const cli_args *a, const char *opt, const char *text, double *lo, double *hi) {
    const char *end;
    double v0, v1;
    if (!scan_double(text, &end, &v0) || *end != ':' || !scan_double(end + 1, &end, &v1) ||
        *end != '\0')
        return cli_usage_error(a, "--%s: expected LO:HI such as 100:1500, got '%s'", opt, text);
    if (!(v0 < v1))
        return cli_usage_error(a, "--%s: LO must be less than HI, got '%s'", opt, text);
    *lo = v0;
    *hi = v1;
    return 0;
}

/* Parses "AxBxC" of three numbers into out (ints when is_int). */
static int
scan_triple(const char *s, size_t len, int is_int, double out[3]) {
    char buf[256];
    if (len == 0 || len >= sizeof buf)
        return 0;
    memcpy(buf, s, len);
    buf[len] = '\0';
    char *p = buf;
    const char *end;
    for (int i = 0; i < 3; i++) {
        if (is_int) {
            long v;
            if (!isdigit((unsigned char)*p) || !scan_long(p, &end, &v))
                return 0;
            out[i] = (double)v;
        } else {
            /* a number ends at the next 'x': strtod alone read "0x1" of
               "1x0x1" as one hexadecimal number */
            char *sep = strpbrk(p, "xX");
            if (i == 2 && sep)
                return 0;
            if (sep)
                *sep = '\0';
            if (!scan_double(p, &end, &out[i]) || (sep && *end != '\0'))
                return 0;
            if (sep) {
                *sep = 'x';
                end = sep;
            }
        }
        p = buf + (end - buf);
        if (i < 2) {
            if (*p != 'x' && *p != 'X')
                return 0;
            p++;
        }
    }
    return *p == '\0';
}

int
cli_parse_raw(const cli_args *a, const char *opt, const char *text, vv_raw_params *p) {
    vv_raw_params_init(p);
    const char *s = text;
    int field = 0;
    int have_endian = 0, have_spacing = 0, have_skip = 0;
    while (1) {
        const char *colon = strchr(s, ':');
        size_t len = colon ? (size_t)(colon - s) : strlen(s);
        if (field == 0) {
            double d[3];
            if (!scan_triple(s, len, 1, d))
                return cli_usage_error(a, "--%s: expected dimensions WxHxD first, got '%.*s'", opt,
                                       (int)len, s);
            for (int i = 0; i < 3; i++) {
                if (d[i] < 1 || d[i] > VV_VOLUME_MAX_DIM)
                    return cli_usage_error(a, "--%s: each dimension must be 1..%d, got '%.*s'", opt,
                                           VV_VOLUME_MAX_DIM, (int)len, s);
                p->dims[i] = (int)d[i];
            }
        } else if (field == 1) {
            char name[32];
            if (len == 0 || len >= sizeof name)
                goto bad_type;
            memcpy(name, s, len);
            name[len] = '\0';
            if (vv_voxel_type_parse(name, &p->type) != VV_OK)
                goto bad_type;
        } else if ((len == 2 && strncmp(s, "be", 2) == 0) ||
                   (len == 2 && strncmp(s, "le", 2) == 0)) {
            if (have_endian)
                return cli_usage_error(a, "--%s: byte order given twice in '%s'", opt, text);
            have_endian = 1;
            p->big_endian = s[0] == 'b';
        } else if (len > 5 && strncmp(s, "skip=", 5) == 0) {
            char buf[32];
            if (have_skip || len - 5 >= sizeof buf)
                goto bad_field;
            memcpy(buf, s + 5, len - 5);
            buf[len - 5] = '\0';
            char *e;
            errno = 0;
            if (!isdigit((unsigned char)buf[0]))
                goto bad_field;
            unsigned long long v = strtoull(buf, &e, 10);
            if (*e != '\0' || errno == ERANGE)
                goto bad_field;
            p->header_skip = (uint64_t)v;
            have_skip = 1;
        } else {
            double d[3];
            if (have_spacing || !scan_triple(s, len, 0, d))
                goto bad_field;
            for (int i = 0; i < 3; i++) {
                if (!(d[i] > 0))
                    return cli_usage_error(a, "--%s: voxel spacing must be > 0, got '%.*s'", opt,
                                           (int)len, s);
                p->spacing[i] = d[i];
            }
            have_spacing = 1;
        }
        field++;
        if (!colon)
            break;
        s = colon + 1;
    }
    if (field < 2)
        return cli_usage_error(a, "--%s: expected WxHxD:TYPE (e.g. 256x256x128:u16:le), got '%s'",
                               opt, text);
    return 0;
bad_type:
    return cli_usage_error(a, "--%s: unknown voxel type in '%s' (u8 i8 u16 i16 u32 i32 f32 f64)",
                           opt, text);
bad_field:
    return cli_usage_error(a,
                           "--%s: cannot understand '%.*s' in '%s' (expected be, le, "
                           "SXxSYxSZ or skip=N)",
                           opt, (int)strcspn(s, ":"), s, text);
}

int
cli_parse_point(const cli_args *a, const char *opt, const char *text, double out[3],
                int *is_voxel) {
    const char *p = text, *end;
    *is_voxel = 0;
    if (strncmp(p, "voxel:", 6) == 0) {
        *is_voxel = 1;
        p += 6;
    } else if (strncmp(p, "world:", 6) == 0) {
        p += 6;
    }
    for (int i = 0; i < 3; i++) {
        if (!scan_double(p, &end, &out[i]))
            goto bad;
        p = end;
        if (i < 2) {
            if (*p != ',')
                goto bad;
            p++;
        }
    }
    if (*p == '\0')
        return 0;
bad:
    return cli_usage_error(a,
                           "--%s: expected a point X,Y,Z (world) or voxel:I,J,K (voxel "
                           "indices), got '%s'",
                           opt, text);
}

int
cli_parse_roi(const cli_args *a, const char *opt, const char *text, int lo[3], int hi[3]) {
    const char *p = text, *end;
    for (int i = 0; i < 6; i++) {
        long v;
        if (!scan_long(p, &end, &v) || v < 0 || v > VV_VOLUME_MAX_DIM)
            goto bad;
        if (i < 3)
            lo[i] = (int)v;
        else
            hi[i - 3] = (int)v;
        p = end;
        char sep = i == 2 ? ':' : ',';
        if (i < 5) {
            if (*p != sep)
                goto bad;
            p++;
        }
    }
    if (*p == '\0')
        return 0;
bad:
    return cli_usage_error(a, "--%s: expected a voxel box I0,J0,K0:I1,J1,K1 (inclusive), got '%s'",
                           opt, text);
}

int
cli_parse_plane(const cli_args *a, const char *opt, const char *text, vv_cut_plane *pl) {
    const char *p = text, *end;
    double v[6];
    for (int i = 0; i < 6; i++) {
        if (!scan_double(p, &end, &v[i]))
            goto bad;
        p = end;
        char sep = i == 2 ? ':' : ',';
        if (i < 5) {
            if (*p != sep)
                goto bad;
            p++;
        }
    }
    if (*p != '\0' || !(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] > 0))
        goto bad;
    pl->point = vv_vec3_make(v[0], v[1], v[2]);
    pl->normal = vv_vec3_normalize(vv_vec3_make(v[3], v[4], v[5]));
    return 0;
bad:
    return cli_usage_error(a,
                           "--%s: expected a plane PX,PY,PZ:NX,NY,NZ (a world point and a "
                           "non-zero normal; keeps the side the normal points to), got '%s'",
                           opt, text);
}
