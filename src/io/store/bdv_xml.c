/*
 * BigDataViewer's dataset XML (Pietzsch, Saalfeld, Preibisch and Tomancak,
 * "BigDataViewer: visualization and processing for large image data sets",
 * Nature Methods 12, 2015; the SpimData XML Fiji's BigDataViewer writes),
 * the entry a Fiji user has to a dataset: one row of the format table. The
 * XML names the HDF5 file holding the pyramids (ImageLoader format
 * "bdv.hdf5", <hdf5 type="relative">), its ViewSetups become the volume's
 * channels (in the order of their ids; a setup's name is its channel's
 * name), its Timepoints (range, pattern or list) its time steps, and each
 * view's registration -- the ViewTransforms of (timepoint, setup), affines
 * composed first to last as SpimData composes them -- its placement in the
 * world: level l of mipmap factors f then maps its voxel (i, j, k) to
 * A (f o (i, j, k) + (f - 1) / 2), its direction the unit columns of A
 * diag(f) and its spacing their lengths. The voxels are read through the
 * HDF5 pyramid's store (hdf5_pyramid.c), unsigned 16-bit stored as int16
 * read as BigDataViewer reads it (bit for bit). An ImageLoader of format
 * "bdv.n5" (<n5 type="relative">) names an N5 container instead, read
 * through the N5 reader (n5.c: vv_n5_bdv_store, group setup<S>/timepoint<T>).
 *
 * The XML is parsed by libxml2, a third party's parser: the row runs in the
 * reader sandbox, which reads beneath the XML's folder only; the HDF5 file
 * must lie there (a relative path without "..", as Fiji writes it).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <libxml/parser.h>
#include <libxml/tree.h>

#include "core/internal.h"
#include "io/store/pyramid.h"
#include "volvis/sys/format.h"

#define BDV_MAX_SETUPS 1024
#define BDV_MAX_TIMEPOINTS 100000
#define BDV_MAX_XML ((long)64 << 20)
#define BDV_MAX_ID (BDV_MAX_TIMEPOINTS * 10) /* a time point's id at most */

/* What the XML says of the dataset. */
typedef struct bdv_doc {
    char h5[4096]; /* the HDF5 file (or N5 container), resolved beside the XML */
    int n5;        /* 1: ImageLoader format bdv.n5 (h5 names the container) */
    int n_setups, n_times;
    int setup_id[BDV_MAX_SETUPS];
    char setup_name[BDV_MAX_SETUPS][VV_CHANNEL_NAME_MAX];
    int *timepoint;      /* n_times ids */
    unsigned char *seen; /* a bit per id 0 .. BDV_MAX_ID: which are in timepoint */
    vv_unit unit;        /* the voxel size's unit (the first setup's) */
    xmlDoc *doc;
    xmlNode *root;
} bdv_doc;

static xmlNode *
child(xmlNode *n, const char *name) {
    for (xmlNode *c = n ? n->children : NULL; c; c = c->next)
        if (c->type == XML_ELEMENT_NODE && !strcmp((const char *)c->name, name))
            return c;
    return NULL;
}

static xmlNode *
next_named(xmlNode *n, const char *name) {
    for (n = n ? n->next : NULL; n; n = n->next)
        if (n->type == XML_ELEMENT_NODE && !strcmp((const char *)n->name, name))
            return n;
    return NULL;
}

/* The text of @p n's child @p name, copied into @p buf (@p cap bytes,
 * whitespace trimmed); 0 when absent or too long. */
static int
child_text(xmlNode *n, const char *name, char *buf, size_t cap) {
    xmlNode *c = child(n, name);
    xmlChar *t = c ? xmlNodeGetContent(c) : NULL;
    if (!t)
        return 0;
    const char *a = (const char *)t;
    while (*a == ' ' || *a == '\t' || *a == '\n' || *a == '\r')
        a++;
    size_t len = strlen(a);
    while (len > 0 &&
           (a[len - 1] == ' ' || a[len - 1] == '\t' || a[len - 1] == '\n' || a[len - 1] == '\r'))
        len--;
    const int ok = len < cap;
    if (ok) {
        memcpy(buf, a, len);
        buf[len] = '\0';
    }
    xmlFree(t);
    return ok;
}

/* An integer of @p text (whole); 0 when not one. */
static int
parse_int(const char *text, int *v) {
    char *end;
    errno = 0;
    const long x = strtol(text, &end, 10);
    if (end == text || *end || errno || x < 0 || x > BDV_MAX_ID)
        return 0;
    *v = (int)x;
    return 1;
}

/* Adds time point @p id (0 .. BDV_MAX_ID) to @p d (each once, at most
 * BDV_MAX_TIMEPOINTS; a bit per id tells which are in: patterns that
 * repeat a range cost its length each time, never its square). */
static vv_status
add_timepoint(bdv_doc *d, int id, const char *xml) {
    if (!d->seen && !(d->seen = calloc(BDV_MAX_ID / 8 + 1, 1)))
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    if (d->seen[id / 8] & (1u << (id % 8)))
        return VV_OK;
    if (d->n_times == BDV_MAX_TIMEPOINTS)
        return vv_error_set(VV_ERR_LIMIT, "%s: over %d time points", xml, BDV_MAX_TIMEPOINTS);
    if (d->n_times % 256 == 0) {
        int *t = realloc(d->timepoint, sizeof(int) * (size_t)(d->n_times + 256));
        if (!t)
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        d->timepoint = t;
    }
    d->seen[id / 8] |= (unsigned char)(1u << (id % 8));
    d->timepoint[d->n_times++] = id;
    return VV_OK;
}

/* An integer pattern, as SpimData writes one ("0-9", "0, 2, 4", "0-10:2"). */
static vv_status
parse_pattern(bdv_doc *d, const char *text, const char *xml) {
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", text);
    vv_status s = VV_OK;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok && s == VV_OK;
         tok = strtok_r(NULL, ",", &save)) {
        while (*tok == ' ')
            tok++;
        int a = 0, b = 0, step = 1, n = 0;
        char tail = 0;
        if ((n = sscanf(tok, "%d-%d:%d %c", &a, &b, &step, &tail)) == 3 ||
            (n = sscanf(tok, "%d-%d %c", &a, &b, &tail)) == 2) {
            if (n == 2)
                step = 1;
        } else if (sscanf(tok, "%d %c", &a, &tail) == 1) {
            b = a;
        } else {
            return vv_error_set(VV_ERR_FORMAT, "%s: Timepoints pattern \"%s\" is not integers", xml,
                                text);
        }
        if (a < 0 || b < a || b > BDV_MAX_ID || step < 1 ||
            (long)(b - a) / step >= BDV_MAX_TIMEPOINTS)
            return vv_error_set(VV_ERR_FORMAT, "%s: Timepoints pattern \"%s\" out of range", xml,
                                text);
        /* long: the step past b near INT_MAX must not overflow an int */
        for (long t = a; t <= b && s == VV_OK; t += step)
            s = add_timepoint(d, (int)t, xml);
    }
    return s;
}

static vv_status
parse_timepoints(bdv_doc *d, xmlNode *tp, const char *xml) {
    if (!tp)
        return vv_error_set(VV_ERR_FORMAT, "%s: no Timepoints", xml);
    xmlChar *type = xmlGetProp(tp, (const xmlChar *)"type");
    char text[4096];
    vv_status s = VV_OK;
    if (type && !strcmp((const char *)type, "range")) {
        char a[64], b[64];
        int first = 0, last = 0;
        if (!child_text(tp, "first", a, sizeof a) || !child_text(tp, "last", b, sizeof b) ||
            !parse_int(a, &first) || !parse_int(b, &last) || last < first ||
            last - first >= BDV_MAX_TIMEPOINTS)
            s = vv_error_set(VV_ERR_FORMAT, "%s: Timepoints range without a first and last", xml);
        for (int t = first; s == VV_OK && t <= last; t++)
            s = add_timepoint(d, t, xml);
    } else if (type && !strcmp((const char *)type, "pattern")) {
        s = child_text(tp, "integerpattern", text, sizeof text)
                ? parse_pattern(d, text, xml)
                : vv_error_set(VV_ERR_FORMAT, "%s: Timepoints pattern without integerpattern", xml);
    } else if (type && !strcmp((const char *)type, "list")) {
        for (xmlNode *t = child(tp, "Timepoint"); t && s == VV_OK; t = next_named(t, "Timepoint")) {
            int id;
            s = child_text(t, "id", text, sizeof text) && parse_int(text, &id)
                    ? add_timepoint(d, id, xml)
                    : vv_error_set(VV_ERR_FORMAT, "%s: a Timepoint without an id", xml);
        }
    } else {
        s = vv_error_set(VV_ERR_FORMAT, "%s: Timepoints of type \"%s\" (range, pattern, list)", xml,
                         type ? (const char *)type : "");
    }
    xmlFree(type);
    if (s == VV_OK && d->n_times == 0)
        s = vv_error_set(VV_ERR_FORMAT, "%s: no time point", xml);
    return s;
}

/* The HDF5 file the ImageLoader names, beside the XML: a relative path
 * without "..". */
static vv_status
resolve_h5(bdv_doc *d, xmlNode *loader, const char *path, const char *xml) {
    xmlChar *fmt = loader ? xmlGetProp(loader, (const xmlChar *)"format") : NULL;
    const int hdf5 = fmt && !strcmp((const char *)fmt, "bdv.hdf5");
    d->n5 = fmt && !strcmp((const char *)fmt, "bdv.n5");
    vv_status s = VV_OK;
    if (!hdf5 && !d->n5)
        s = vv_error_set(VV_ERR_UNSUPPORTED,
                         "%s: ImageLoader format \"%s\" (VolVis reads bdv.hdf5 and bdv.n5 "
                         "datasets)",
                         xml, fmt ? (const char *)fmt : "");
    xmlFree(fmt);
    if (s != VV_OK)
        return s;
    const char *tag = d->n5 ? "n5" : "hdf5", *what = d->n5 ? "n5 container" : "hdf5 file";
    xmlNode *h = child(loader, tag);
    char name[4096];
    xmlChar *type = h ? xmlGetProp(h, (const xmlChar *)"type") : NULL;
    const int absolute = type && !strcmp((const char *)type, "absolute");
    xmlFree(type);
    if (!h || !child_text(loader, tag, name, sizeof name) || !name[0])
        return vv_error_set(VV_ERR_FORMAT, "%s: the ImageLoader names no %s", xml, what);
    if (absolute || name[0] == '/' || !strcmp(name, "..") || !strncmp(name, "../", 3) ||
        strstr(name, "/../") || (strlen(name) >= 3 && !strcmp(name + strlen(name) - 3, "/..")))
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: the %s \"%s\" is not a relative path inside the XML's "
                            "folder (the only place read)",
                            xml, what, name);
    const char *slash = strrchr(path, '/');
    const size_t dir = slash ? (size_t)(slash - path) + 1 : 0, len = strlen(name);
    if (dir + len + 1 > sizeof d->h5)
        return vv_error_set(VV_ERR_LIMIT, "%s: the %s's path is too long", xml, what);
    memcpy(d->h5, path, dir);
    memcpy(d->h5 + dir, name, len + 1);
    /* a symbolic link (the file's or a folder's on its way) may still lead
     * out of the XML's folder: compare the real paths (a file that does not
     * exist is refused when opened) */
    char folder[4096];
    snprintf(folder, sizeof folder, "%.*s", dir ? (int)dir : 1, dir ? path : ".");
    char *rdir = realpath(folder, NULL), *rfile = realpath(d->h5, NULL);
    int inside = 1;
    if (rdir && rfile) {
        const size_t n = strlen(rdir);
        inside = !strncmp(rfile, rdir, n) && (rfile[n] == '/' || (n == 1 && rdir[0] == '/'));
    }
    free(rdir);
    free(rfile);
    if (!inside)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: the %s \"%s\" resolves outside the XML's folder (a "
                            "link)",
                            xml, what, name);
    return VV_OK;
}

static void
doc_free(bdv_doc *d) {
    if (!d)
        return;
    xmlFreeDoc(d->doc);
    free(d->timepoint);
    free(d->seen);
    free(d);
}

/* A <!DOCTYPE>: stop before its internal subset declares anything. */
static void
stop_at_doctype(void *ctx, const xmlChar *name, const xmlChar *public_id,
                const xmlChar *system_id) {
    (void)name;
    (void)public_id;
    (void)system_id;
    xmlStopParser((xmlParserCtxtPtr)ctx);
}

xmlDoc *
vv_bdv_xml_read(const char *path, int *doctype) {
    *doctype = 0;
    xmlParserCtxtPtr c = xmlNewParserCtxt();
    if (!c)
        return NULL;
    c->sax->internalSubset = stop_at_doctype;
    xmlDoc *doc =
        xmlCtxtReadFile(c, path, NULL, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (c->errNo == XML_ERR_USER_STOP) {
        *doctype = 1;
        xmlFreeDoc(doc);
        doc = NULL;
    }
    xmlFreeParserCtxt(c);
    return doc;
}

/* Parses the XML at @p path. */
static vv_status
doc_open(bdv_doc **out, const char *path) {
    *out = NULL;
    const char *xml = vv_path_basename(path);
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) /* a FIFO would block the open */
        return vv_error_set(VV_ERR_FORMAT, "%s: not a regular file", xml);
    FILE *f = fopen(path, "rb");
    if (!f) {
        const int e = errno;
        return vv_error_set(VV_ERR_IO, "%s: %s", xml, strerror(e));
    }
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    fclose(f);
    if (size < 0 || size > BDV_MAX_XML)
        return vv_error_set(VV_ERR_LIMIT, "%s: %ld bytes, over the 64 MiB a dataset XML may have",
                            xml, size);
    bdv_doc *d = calloc(1, sizeof *d);
    if (!d)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    /* no network, no document type (no entities, no DTD) */
    int doctype = 0;
    d->doc = vv_bdv_xml_read(path, &doctype);
    d->root = d->doc ? xmlDocGetRootElement(d->doc) : NULL;
    vv_status s = VV_OK;
    if (doctype)
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: a <!DOCTYPE> (entities and DTDs are refused in a dataset XML)", xml);
    else if (!d->root)
        s = vv_error_set(VV_ERR_FORMAT, "%s: not well-formed XML", xml);
    else if (strcmp((const char *)d->root->name, "SpimData"))
        s = vv_error_set(VV_ERR_FORMAT, "%s: the root element is <%s>, not <SpimData>", xml,
                         (const char *)d->root->name);
    xmlNode *seq = s == VV_OK ? child(d->root, "SequenceDescription") : NULL;
    if (s == VV_OK && !seq)
        s = vv_error_set(VV_ERR_FORMAT, "%s: no SequenceDescription", xml);
    if (s == VV_OK)
        s = resolve_h5(d, child(seq, "ImageLoader"), path, xml);
    d->unit = VV_UNIT_UNKNOWN;
    /* the setups, by id */
    for (xmlNode *vs = child(child(seq, "ViewSetups"), "ViewSetup"); vs && s == VV_OK;
         vs = next_named(vs, "ViewSetup")) {
        char text[256];
        int id;
        if (!child_text(vs, "id", text, sizeof text) || !parse_int(text, &id) || id > 99999) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: a ViewSetup without an id", xml);
            break;
        }
        if (d->n_setups == BDV_MAX_SETUPS) {
            s = vv_error_set(VV_ERR_LIMIT, "%s: over %d ViewSetups", xml, BDV_MAX_SETUPS);
            break;
        }
        int at = d->n_setups++;
        while (at > 0 && d->setup_id[at - 1] > id) {
            d->setup_id[at] = d->setup_id[at - 1];
            memcpy(d->setup_name[at], d->setup_name[at - 1], VV_CHANNEL_NAME_MAX);
            at--;
        }
        if (at > 0 && d->setup_id[at - 1] == id) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: two ViewSetups of id %d", xml, id);
            break;
        }
        d->setup_id[at] = id;
        if (!child_text(vs, "name", d->setup_name[at], VV_CHANNEL_NAME_MAX))
            snprintf(d->setup_name[at], VV_CHANNEL_NAME_MAX, "setup %d", id);
        char unit[64];
        if (d->unit == VV_UNIT_UNKNOWN &&
            child_text(child(vs, "voxelSize"), "unit", unit, sizeof unit))
            d->unit = vv_unit_parse(unit);
    }
    if (s == VV_OK && d->n_setups == 0)
        s = vv_error_set(VV_ERR_FORMAT, "%s: no ViewSetup", xml);
    if (s == VV_OK)
        s = parse_timepoints(d, child(seq, "Timepoints"), xml);
    if (s != VV_OK) {
        doc_free(d);
        return s;
    }
    *out = d;
    return VV_OK;
}

/* The 3x4 affine of view (@p timepoint, @p setup): its ViewTransforms
 * composed first to last (A = T0 T1 ... Tn). A view without a registration
 * is the identity: voxels of one unit. */
static vv_status
view_affine(const bdv_doc *d, int timepoint, int setup, double A[3][4], const char *xml) {
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            A[r][c] = r == c;
    for (xmlNode *vr = child(child(d->root, "ViewRegistrations"), "ViewRegistration"); vr;
         vr = next_named(vr, "ViewRegistration")) {
        xmlChar *t = xmlGetProp(vr, (const xmlChar *)"timepoint");
        xmlChar *s = xmlGetProp(vr, (const xmlChar *)"setup");
        int ti = -1, si = -1;
        const int mine = t && s && parse_int((const char *)t, &ti) &&
                         parse_int((const char *)s, &si) && ti == timepoint && si == setup;
        xmlFree(t);
        xmlFree(s);
        if (!mine)
            continue;
        for (xmlNode *vt = child(vr, "ViewTransform"); vt; vt = next_named(vt, "ViewTransform")) {
            char text[1024];
            double m[12];
            char tail = 0;
            if (!child_text(vt, "affine", text, sizeof text) ||
                sscanf(text, "%lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %c", &m[0], &m[1],
                       &m[2], &m[3], &m[4], &m[5], &m[6], &m[7], &m[8], &m[9], &m[10], &m[11],
                       &tail) != 12)
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s: a ViewTransform of view (%d, %d) is not an affine of "
                                    "12 numbers",
                                    xml, timepoint, setup);
            for (int k = 0; k < 12; k++)
                if (!isfinite(m[k]) || fabs(m[k]) > 1e30)
                    return vv_error_set(VV_ERR_FORMAT,
                                        "%s: a ViewTransform of view (%d, %d) is not finite", xml,
                                        timepoint, setup);
            double B[3][4]; /* A * M */
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 4; c++) {
                    double v = c == 3 ? A[r][3] : 0;
                    for (int k = 0; k < 3; k++)
                        v += A[r][k] * m[4 * k + c];
                    B[r][c] = v;
                }
            memcpy(A, B, sizeof B);
        }
        return VV_OK;
    }
    return VV_OK;
}

/* Each level of @p st (level geometry in level-0 voxels: spacing the
 * factors f, origin (f - 1) / 2) placed by @p A. */
static vv_status
place_levels(vv_store *st, double A[3][4], vv_unit unit, const char *xml) {
    for (int l = 0; l < st->n_levels; l++) {
        vv_volume *h = st->lv[l].hdr;
        double f[3], o[3];
        for (int k = 0; k < 3; k++) {
            f[k] = h->spacing[k];
            o[k] = h->origin[k];
        }
        double L[3][3];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                L[r][c] = A[r][c] * f[c];
        for (int c = 0; c < 3; c++) {
            const double len = sqrt(L[0][c] * L[0][c] + L[1][c] * L[1][c] + L[2][c] * L[2][c]);
            if (!(len > 0) || !isfinite(len))
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s: the view's affine is singular (axis %d has no length)",
                                    xml, c);
            h->spacing[c] = len;
            for (int r = 0; r < 3; r++)
                h->direction[3 * r + c] = L[r][c] / len;
        }
        for (int r = 0; r < 3; r++) {
            h->origin[r] = A[r][3] + A[r][0] * o[0] + A[r][1] * o[1] + A[r][2] * o[2];
            if (!isfinite(h->origin[r]))
                return vv_error_set(VV_ERR_FORMAT,
                                    "%s: the view's affine puts level %d's origin at infinity "
                                    "(axis %d)",
                                    xml, l, r);
        }
        h->unit = unit;
    }
    return VV_OK;
}

/* The store of channel (setup) @p channel at time step @p time of the
 * dataset at @p path, placed; @p info (may be NULL) gets the counts and the
 * setup's name. */
static vv_status
bdv_open_store(vv_store *st, const char *path, int channel, int time, vv_load_info *info) {
    memset(st, 0, sizeof *st);
    const char *xml = vv_path_basename(path);
    bdv_doc *d = NULL;
    vv_status s = doc_open(&d, path);
    if (s != VV_OK)
        return vv_error_prefix(s, "bdv");
    const int c = channel < 0 ? 0 : channel, t = time < 0 ? 0 : time;
    if (c >= d->n_setups)
        s = vv_error_set(VV_ERR_INVALID, "bdv: %s: channel %d asked, the dataset has %d setups",
                         xml, c, d->n_setups);
    else if (t >= d->n_times)
        s = vv_error_set(VV_ERR_INVALID,
                         "bdv: %s: time step %d asked, the dataset has %d time points", xml, t,
                         d->n_times);
    double A[3][4];
    if (s == VV_OK)
        s = view_affine(d, d->timepoint[t], d->setup_id[c], A, xml);
    if (s == VV_OK) {
        s = d->n5 ? vv_n5_bdv_store(st, d->h5, d->setup_id[c], d->timepoint[t])
                  : vv_h5_bdv_store(st, d->h5, d->setup_id[c], d->timepoint[t]);
        if (s != VV_OK)
            s = vv_error_prefix(s, "bdv: %s: %s", xml, vv_path_basename(d->h5));
    }
    if (s == VV_OK)
        s = place_levels(st, A, d->unit, xml);
    if (s == VV_OK) {
        st->name = "bdv";
        st->n_channels = d->n_setups;
        st->n_times = d->n_times;
        if (info) {
            info->n_channels = d->n_setups;
            info->n_times = d->n_times;
            info->n_levels = st->n_levels;
            snprintf(info->channel_name, sizeof info->channel_name, "%s", d->setup_name[c]);
        }
    }
    doc_free(d);
    if (s != VV_OK)
        vv_store_close(st);
    return s;
}

/* Level opt->level of a channel at a time step, whole. */
static vv_status
bdv_read(vv_volume **out, const char *path, const vv_load_options *opt) {
    *out = NULL;
    vv_store st;
    vv_status s = bdv_open_store(&st, path, opt->channel, opt->time, opt->info);
    if (s != VV_OK)
        return s;
    const int level = opt->level > 0 ? opt->level : 0;
    if (level >= st.n_levels)
        s = vv_error_set(VV_ERR_INVALID, "bdv: %s: level %d asked, the dataset has %d",
                         vv_path_basename(path), level, st.n_levels);
    if (s == VV_OK && (s = vv_store_read_level(&st, level, out)) != VV_OK)
        s = vv_error_prefix(s, "bdv: %s", vv_path_basename(path));
    vv_store_close(&st);
    return s;
}

/* A SpimData document: its root element in the head (after an XML
 * declaration and comments). */
static int
bdv_looks_like(const vv_format_probe *p, int deep) {
    if (deep || p->is_dir)
        return 0;
    const char *t = p->text;
    while (*t == ' ' || *t == '\t' || *t == '\r' || *t == '\n')
        t++;
    if (strncmp(t, "<?xml", 5) && strncmp(t, "<SpimData", 9) && strncmp(t, "<!--", 4))
        return 0;
    return strstr(t, "<SpimData") != NULL;
}

static const char *const bdv_extensions[] = {"xml", NULL};

const vv_format_record vv_format_bdv_xml = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "bdv",
    .title = "BigDataViewer XML",
    .extensions = bdv_extensions,
    .aliases = NULL,
    .doc = "BigDataViewer's dataset XML (Fiji): its setups as channels, its time points as time "
           "steps, each view's affine as its placement; the voxels from its HDF5 pyramid, read "
           "whole (--level) or out of core by level of detail",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = bdv_looks_like,
    .read = bdv_read,
    .open_store = bdv_open_store,
};
