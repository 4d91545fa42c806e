/*
 * VTK XML UnstructuredGrid (.vtu) files, parsed with libxml2: data arrays
 * inline (ascii or base64 "binary") or appended (raw or base64), zlib
 * compressed or not, UInt32 or UInt64 headers, either byte order ("VTK
 * File Formats", XML file formats).
 *
 * The file-level parts (vv_vtkxml_open, vv_vtkxml_array_bytes) serve the
 * .vti volume reader too (vti_read.c).
 *
 * Hostile files: entity declarations (the "billion laughs" XML bomb) are
 * refused before parsing, libxml2 runs without network access and entity
 * substitution, every array's decoded and decompressed size is checked
 * against what the header says before anything is allocated for it, and
 * truncated base64 or compressed blocks are errors.
 */
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/grid/grid_io_internal.h"
#include "io/io_internal.h"
#include "volvis/grid.h"
#include "volvis/sys/format.h"

#define VTU_FILE_MAX (4ull << 30)

typedef vv_vtkxml vtu;

static int
b64_value(unsigned char ch) {
    if (ch >= 'A' && ch <= 'Z')
        return ch - 'A';
    if (ch >= 'a' && ch <= 'z')
        return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9')
        return ch - '0' + 52;
    if (ch == '+')
        return 62;
    if (ch == '/')
        return 63;
    return -1;
}

/* Decodes base64 characters from *p (whitespace skipped) until @p n bytes
 * are out or a group ends with padding or the text ends. Returns the bytes
 * decoded; *p moves past the groups used. */
static size_t
b64_decode(const unsigned char **p, const unsigned char *end, unsigned char *out, size_t n) {
    size_t k = 0;
    while (k < n) {
        int v[4], m = 0;
        const unsigned char *q = *p;
        while (m < 4 && q < end) {
            const unsigned char ch = *q++;
            if (ch == ' ' || ch == '\n' || ch == '\r' || ch == '\t')
                continue;
            if (ch == '=') {
                v[m++] = -2;
                continue;
            }
            const int x = b64_value(ch);
            if (x < 0) {
                q--;
                break;
            }
            v[m++] = x;
        }
        if (m < 4)
            return k; /* truncated group */
        *p = q;
        const int pad = (v[2] == -2) + (v[3] == -2);
        if (v[0] < 0 || v[1] < 0 || (v[2] == -2 && v[3] != -2))
            return k;
        const uint32_t w = (uint32_t)v[0] << 18 | (uint32_t)v[1] << 12 |
                           (uint32_t)(v[2] < 0 ? 0 : v[2]) << 6 | (uint32_t)(v[3] < 0 ? 0 : v[3]);
        const unsigned char b[3] = {(unsigned char)(w >> 16), (unsigned char)(w >> 8),
                                    (unsigned char)w};
        for (int i = 0; i < 3 - pad && k < n; i++)
            out[k++] = b[i];
        if (pad)
            return k;
    }
    return k;
}

static uint64_t
header_word(const vtu *v, const unsigned char *p) {
    return (uint64_t)vv_gtype_get(p, v->header64 ? VV_GT_U64 : VV_GT_U32, v->big_endian);
}

/* An uncompressed base64 array: its byte-count word and its data, encoded
 * separately (VTK) or together. */
static vv_status
plain_base64(const vtu *v, const unsigned char *p, const unsigned char *end, size_t expect,
             const char *name, unsigned char **out) {
    const size_t ws = v->header64 ? 8 : 4;
    unsigned char hdr[8];
    const unsigned char *q = p;
    if (b64_decode(&q, end, hdr, ws) != ws)
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 header", v->path, name);
    size_t nbytes = (size_t)header_word(v, hdr);
    if (nbytes != expect)
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: %zu bytes, expected %zu", v->path, name,
                            nbytes, expect);
    unsigned char *buf = malloc(expect ? expect : 1);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
    size_t got;
    if (ws % 3 != 0 && memchr(p, '=', (size_t)(q - p))) {
        got = b64_decode(&q, end, buf, expect);
    } else {
        const unsigned char *q2 = p;
        unsigned char *all = malloc(ws + expect);
        if (!all) {
            free(buf);
            return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
        }
        got = b64_decode(&q2, end, all, ws + expect);
        got = got >= ws ? got - ws : 0;
        memcpy(buf, all + ws, got);
        free(all);
    }
    if (got != expect) {
        free(buf);
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 data (%zu of %zu bytes)",
                            v->path, name, got, expect);
    }
    *out = buf;
    return VV_OK;
}

/* An uncompressed raw (appended) array: its byte-count word and its data. */
static vv_status
plain_raw(const vtu *v, const unsigned char *p, const unsigned char *end, size_t expect,
          const char *name, unsigned char **out) {
    const size_t ws = v->header64 ? 8 : 4;
    if ((size_t)(end - p) < ws)
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated", v->path, name);
    size_t nbytes = (size_t)header_word(v, p);
    if (nbytes != expect || expect > (size_t)(end - p) - ws)
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: %zu bytes (expected %zu, %zu left)",
                            v->path, name, nbytes, expect, (size_t)(end - p) - ws);
    unsigned char *buf = malloc(expect ? expect : 1);
    if (!buf)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
    memcpy(buf, p + ws, expect);
    *out = buf;
    return VV_OK;
}

/* A zlib-compressed array's header [blocks, block size, last block size,
 * compressed sizes...], checked against @p expect: *@p h (malloc'ed, the
 * whole header), the block counts, and *@p q past the header. */
static vv_status
zlib_header(const vtu *v, const unsigned char *p, const unsigned char *end, int base64,
            size_t expect, const char *name, unsigned char **h, size_t *nb, size_t *bs,
            size_t *last, const unsigned char **q) {
    const size_t ws = v->header64 ? 8 : 4;
    unsigned char first[24];
    *q = p;
    if (base64) {
        const unsigned char *q1 = p;
        if (b64_decode(&q1, end, first, 3 * ws) != 3 * ws)
            return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 header", v->path,
                                name);
    } else {
        if ((size_t)(end - p) < 3 * ws)
            return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated header", v->path, name);
        memcpy(first, p, 3 * ws);
    }
    *nb = (size_t)header_word(v, first);
    *bs = (size_t)header_word(v, first + ws);
    *last = (size_t)header_word(v, first + 2 * ws);
    if (*last == 0)
        *last = *bs;
    const size_t total = *nb == 0 ? 0 : (*nb - 1) * *bs + *last;
    if (*nb > (1u << 24) || *bs == 0 || total != expect)
        return vv_error_set(VV_ERR_FORMAT,
                            "%s: array %s: compressed header says %zu blocks of %zu bytes "
                            "(%zu in all), expected %zu",
                            v->path, name, *nb, *bs, total, expect);
    const size_t hsize = (3 + *nb) * ws;
    if (!(*h = malloc(hsize)))
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
    if (base64) {
        if (b64_decode(q, end, *h, hsize) != hsize)
            return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 header", v->path,
                                name);
    } else {
        if ((size_t)(end - *q) < hsize)
            return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated header", v->path, name);
        *q += hsize;
        memcpy(*h, p, hsize);
    }
    return VV_OK;
}

/* The compressed blocks after the header at @p q: their sizes checked
 * against the file, decoded from base64 into *@p cbuf (malloc'ed) when
 * @p base64; *@p cdata points at them. */
static vv_status
zlib_blocks(const vtu *v, const unsigned char *q, const unsigned char *end, int base64,
            const unsigned char *h, size_t nb, const char *name, unsigned char **cbuf,
            const unsigned char **cdata) {
    const size_t ws = v->header64 ? 8 : 4;
    size_t csum = 0;
    for (size_t i = 0; i < nb; i++) {
        const uint64_t cs = header_word(v, h + (3 + i) * ws);
        if (cs > (size_t)(end - q) + 16)
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: array %s: block %zu of %llu bytes overruns "
                                "the file",
                                v->path, name, i, (unsigned long long)cs);
        csum += (size_t)cs;
    }
    if (!base64) {
        if (csum > (size_t)(end - q))
            return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated compressed data", v->path,
                                name);
        *cdata = q;
        return VV_OK;
    }
    if (csum > (size_t)(end - q))
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 data", v->path, name);
    if (!(*cbuf = malloc(csum ? csum : 1)))
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
    if (b64_decode(&q, end, *cbuf, csum) != csum)
        return vv_error_set(VV_ERR_FORMAT, "%s: array %s: truncated base64 data", v->path, name);
    *cdata = *cbuf;
    return VV_OK;
}

/* A zlib-compressed array: header, blocks, each block inflated. */
static vv_status
zlib_array(const vtu *v, const unsigned char *p, const unsigned char *end, int base64,
           size_t expect, const char *name, unsigned char **out) {
    const size_t ws = v->header64 ? 8 : 4;
    unsigned char *h = NULL, *cbuf = NULL, *buf = NULL;
    const unsigned char *q, *cdata = NULL;
    size_t nb = 0, bs = 0, last = 0;
    vv_status s = zlib_header(v, p, end, base64, expect, name, &h, &nb, &bs, &last, &q);
    if (s == VV_OK)
        s = zlib_blocks(v, q, end, base64, h, nb, name, &cbuf, &cdata);
    if (s == VV_OK && !(buf = malloc(expect ? expect : 1)))
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
    size_t off = 0, coff = 0;
    for (size_t i = 0; s == VV_OK && i < nb; i++) {
        const size_t cs = (size_t)header_word(v, h + (3 + i) * ws);
        uLongf dl = (uLongf)(i + 1 == nb ? last : bs);
        const uLongf want = dl;
        const int zr = uncompress(buf + off, &dl, cdata + coff, (uLong)cs);
        if (zr != Z_OK || dl != want)
            s = vv_error_set(VV_ERR_FORMAT, "%s: array %s: block %zu does not inflate (zlib %d)",
                             v->path, name, i, zr);
        off += dl;
        coff += cs;
    }
    free(h);
    free(cbuf);
    if (s != VV_OK) {
        free(buf);
        return s;
    }
    *out = buf;
    return VV_OK;
}

/* The raw bytes of one binary array (after its header), @p expect bytes
 * long, from text or appended data starting at @p p. base64: characters;
 * else raw bytes. Allocates *out. */
static vv_status
binary_array(const vtu *v, const unsigned char *p, const unsigned char *end, int base64,
             size_t expect, const char *name, unsigned char **out) {
    *out = NULL;
    if (v->zlib)
        return zlib_array(v, p, end, base64, expect, name, out);
    return base64 ? plain_base64(v, p, end, expect, name, out)
                  : plain_raw(v, p, end, expect, name, out);
}

static char *
prop(xmlNode *n, const char *name) {
    return (char *)xmlGetProp(n, (const xmlChar *)name);
}

static int
is_elem(xmlNode *n, const char *name) {
    return n->type == XML_ELEMENT_NODE && !strcmp((const char *)n->name, name);
}

vv_status
vv_vtkxml_array_bytes(const vv_vtkxml *v, xmlNode *da, size_t nbytes, const char *name,
                      unsigned char **out) {
    *out = NULL;
    char *fmt = prop(da, "format"), *offs = prop(da, "offset");
    vv_status s;
    if (fmt && !strcmp(fmt, "binary")) {
        xmlChar *text = xmlNodeGetContent(da);
        const unsigned char *p = text ? text : (const unsigned char *)"";
        const unsigned char *e = p + strlen((const char *)p);
        while (p < e && (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t'))
            p++;
        s = binary_array(v, p, e, 1, nbytes, name, out);
        xmlFree(text);
    } else if (fmt && !strcmp(fmt, "appended")) {
        char *end;
        const unsigned long long off = offs ? strtoull(offs, &end, 10) : 0;
        if (!offs || *end || !v->appended || off > v->appended_len)
            s = vv_error_set(VV_ERR_FORMAT,
                             "%s: DataArray %s: appended offset \"%s\" is not in "
                             "the appended data",
                             v->path, name, offs ? offs : "");
        else
            s = binary_array(v, v->appended + off, v->appended + v->appended_len,
                             v->appended_base64, nbytes, name, out);
    } else {
        s = vv_error_set(VV_ERR_FORMAT, "%s: DataArray %s: format \"%s\"", v->path, name,
                         fmt ? fmt : "");
    }
    xmlFree(fmt);
    xmlFree(offs);
    return s;
}

/* Reads a DataArray of n tuples x ncomp (ncomp 0: whatever it declares,
 * returned in *ncomp_out) into doubles. */
static vv_status
data_array(const vtu *v, xmlNode *da, size_t n, int ncomp, int *ncomp_out, double **out) {
    *out = NULL;
    char *type = prop(da, "type"), *fmt = prop(da, "format"), *nc = prop(da, "NumberOfComponents"),
         *name = prop(da, "Name");
    vv_status s = VV_OK;
    const char *nm = name ? name : "(unnamed)";
    vv_gtype t;
    int comps = nc ? atoi(nc) : 1;
    unsigned char *raw = NULL;
    double *vals = NULL;
    if (!type || !vv_gtype_parse(type, &t)) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: DataArray %s: type \"%s\"", v->path, nm,
                         type ? type : "");
        goto done;
    }
    if (comps < 1 || comps > 9 || (ncomp > 0 && comps != ncomp)) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: DataArray %s: %d components", v->path, nm, comps);
        goto done;
    }
    const size_t nv = n * (size_t)comps, sz = vv_gtype_size(t);
    if (nv > (size_t)VV_GRID_MAX_CELLS * 8) {
        s = vv_error_set(VV_ERR_LIMIT, "%s: DataArray %s: %zu values", v->path, nm, nv);
        goto done;
    }
    vals = malloc((nv ? nv : 1) * sizeof *vals);
    if (!vals) {
        s = vv_error_set(VV_ERR_NOMEM, "%s: out of memory", v->path);
        goto done;
    }
    if (fmt && !strcmp(fmt, "ascii")) {
        xmlChar *text = xmlNodeGetContent(da);
        vv_gcur c;
        vv_gcur_init(&c, text ? text : (const xmlChar *)"", text ? strlen((char *)text) : 0,
                     v->path);
        s = vv_gcur_values(&c, 0, 0, t, nv, vals, nm);
        xmlFree(text);
        goto done;
    }
    s = vv_vtkxml_array_bytes(v, da, nv * sz, nm, &raw);
    if (s == VV_OK)
        for (size_t i = 0; i < nv; i++)
            vals[i] = vv_gtype_get(raw + i * sz, t, v->big_endian);
done:
    free(raw);
    if (ncomp_out)
        *ncomp_out = comps;
    xmlFree(type);
    xmlFree(fmt);
    xmlFree(nc);
    xmlFree(name);
    if (s != VV_OK) {
        free(vals);
        return s;
    }
    *out = vals;
    return VV_OK;
}

xmlNode *
vv_vtkxml_child(xmlNode *n, const char *name) {
    for (xmlNode *c = n ? n->children : NULL; c; c = c->next)
        if (is_elem(c, name))
            return c;
    return NULL;
}

#define child vv_vtkxml_child

static xmlNode *
named_array(xmlNode *parent, const char *name) {
    for (xmlNode *c = parent ? parent->children : NULL; c; c = c->next)
        if (is_elem(c, "DataArray")) {
            char *nm = prop(c, "Name");
            const int hit = nm && !strcmp(nm, name);
            xmlFree(nm);
            if (hit)
                return c;
        }
    return NULL;
}

static size_t
size_prop(xmlNode *n, const char *name, int *ok) {
    char *s = prop(n, name);
    char *end = NULL;
    long long v = s ? strtoll(s, &end, 10) : -1;
    *ok = s && end && !*end && v >= 0;
    xmlFree(s);
    return *ok ? (size_t)v : 0;
}

static void
silent(void *ctx, const char *msg, ...) {
    (void)ctx;
    (void)msg;
}

/* Entity declarations are refused: no XML bomb reaches the parser. */
static vv_status
vtu_refuse_entities(const unsigned char *data, uint64_t size, const char *path) {
    const size_t scan = size < 65536 ? (size_t)size : 65536;
    for (size_t i = 0; i + 8 <= scan; i++)
        if (!memcmp(data + i, "<!ENTITY", 8) || !memcmp(data + i, "<!DOCTYPE", 9))
            return vv_error_set(VV_ERR_FORMAT,
                                "%s: DOCTYPE or entity declarations are not allowed in a VTK "
                                "XML file (possible XML bomb)",
                                path);
    return VV_OK;
}

/* Cuts the appended data out of what libxml2 parses (raw bytes are not
 * XML): *@p xml is @p data itself when there is none, else a malloc'ed copy
 * without it; v->appended points into @p data. */
static vv_status
vtu_cut_appended(vtu *v, unsigned char *data, uint64_t size, unsigned char **xml, size_t *xml_len) {
    const char *path = v->path;
    *xml = data;
    *xml_len = (size_t)size;
    unsigned char *ad = NULL;
    for (size_t i = 0; i + 13 <= (size_t)size; i++)
        if (!memcmp(data + i, "<AppendedData", 13)) {
            ad = data + i;
            break;
        }
    if (!ad)
        return VV_OK;
    unsigned char *gt = memchr(ad, '>', (size_t)(data + size - ad));
    unsigned char *us = gt ? memchr(gt, '_', (size_t)(data + size - gt)) : NULL;
    /* the closing tag, searched from the end (raw data may hold anything) */
    unsigned char *close = NULL;
    for (unsigned char *q = data + size - 15; us && q > us; q--)
        if (!memcmp(q, "</AppendedData>", 15)) {
            close = q;
            break;
        }
    if (!gt || !us || !close)
        return vv_error_set(VV_ERR_FORMAT, "%s: AppendedData without '_' or its end tag", path);
    v->appended = us + 1;
    v->appended_len = (size_t)(close - us - 1);
    /* the encoding attribute of AppendedData */
    char enc[16] = "";
    for (const unsigned char *e = ad; e + 10 < gt; e++)
        if (!memcmp(e, "encoding=\"", 10)) {
            sscanf((const char *)e + 10, "%15[^\"]", enc);
            break;
        }
    v->appended_base64 = !strcmp(enc, "base64");
    if (!v->appended_base64 && strcmp(enc, "raw"))
        return vv_error_set(VV_ERR_FORMAT, "%s: AppendedData encoding \"%s\"", path, enc);
    unsigned char *x = malloc((size_t)size + 1);
    if (!x)
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory", path);
    const size_t head = (size_t)(gt + 1 - data), tail = (size_t)(data + size - close);
    memcpy(x, data, head);
    memcpy(x + head, close, tail);
    *xml = x;
    *xml_len = head + tail;
    return VV_OK;
}

/* Parses the XML (no network), a one-line error of printable ASCII otherwise. */
static vv_status
vtu_parse(const unsigned char *xml, size_t xml_len, const char *path, xmlDoc **doc) {
    xmlSetGenericErrorFunc(NULL, silent);
    *doc = xmlReadMemory((const char *)xml, (int)(xml_len < (size_t)INT32_MAX ? xml_len : 0), path,
                         NULL, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (*doc)
        return VV_OK;
    const xmlError *xe = xmlGetLastError();
    char msg[160] = "parse error";
    if (xe && xe->message)
        snprintf(msg, sizeof msg, "%s", xe->message);
    msg[strcspn(msg, "\r\n")] = '\0'; /* one line */
    for (char *q = msg; *q; q++)      /* of printable ASCII: libxml2 quotes the bad bytes */
        if ((unsigned char)*q < 0x20 || (unsigned char)*q > 0x7e)
            *q = '?';
    return vv_error_set(VV_ERR_FORMAT, "%s: not well-formed XML (line %d: %s)", path,
                        xe ? xe->line : 0, msg);
}

/* The VTKFile root (type, byte order, header type, compressor): @p type's
 * element in *@p dataset. */
static vv_status
vtkxml_root(vv_vtkxml *v, xmlDoc *doc, const char *type, xmlNode **dataset) {
    const char *path = v->path;
    xmlNode *root = xmlDocGetRootElement(doc);
    if (!root || !is_elem(root, "VTKFile"))
        return vv_error_set(VV_ERR_FORMAT, "%s: the root element is not VTKFile", path);
    vv_status s = VV_OK;
    char *ty = prop(root, "type"), *bo = prop(root, "byte_order"), *ht = prop(root, "header_type"),
         *cp = prop(root, "compressor");
    int ok = ty && !strcmp(ty, type);
    v->big_endian = bo && !strcmp(bo, "BigEndian");
    v->header64 = ht && !strcmp(ht, "UInt64");
    v->zlib = cp && !strcmp(cp, "vtkZLibDataCompressor");
    const int bad_cp = cp && !v->zlib;
    if (!ok || bad_cp)
        s = vv_error_set(bad_cp ? VV_ERR_UNSUPPORTED : VV_ERR_FORMAT,
                         "%s: %s \"%s\" (%s with zlib or no compression)", path,
                         bad_cp ? "compressor" : "type", bad_cp ? cp : (ty ? ty : ""), type);
    xmlFree(ty);
    xmlFree(bo);
    xmlFree(ht);
    xmlFree(cp);
    if (s != VV_OK)
        return s;
    *dataset = child(root, type);
    if (!*dataset)
        return vv_error_set(VV_ERR_FORMAT, "%s: no %s element", path, type);
    return VV_OK;
}

vv_status
vv_vtkxml_open(vv_vtkxml *v, unsigned char *data, uint64_t size, const char *type, xmlDoc **doc,
               unsigned char **xml, xmlNode **dataset) {
    size_t xml_len = 0;
    *doc = NULL;
    *xml = NULL;
    vv_status s;
    if ((s = vtu_refuse_entities(data, size, v->path)) == VV_OK &&
        (s = vtu_cut_appended(v, data, size, xml, &xml_len)) == VV_OK &&
        (s = vtu_parse(*xml, xml_len, v->path, doc)) == VV_OK)
        s = vtkxml_root(v, *doc, type, dataset);
    return s;
}

/* The UnstructuredGrid's one Piece with its point and cell counts, checked
 * against the limits and the file's @p size. */
static vv_status
vtu_piece(vtu *v, xmlNode *grid, uint64_t size, xmlNode **piece, size_t *np, size_t *nc) {
    const char *path = v->path;
    *piece = child(grid, "Piece");
    if (!*piece)
        return vv_error_set(VV_ERR_FORMAT, "%s: no UnstructuredGrid/Piece", path);
    for (xmlNode *c = (*piece)->next; c; c = c->next)
        if (is_elem(c, "Piece"))
            return vv_error_set(VV_ERR_UNSUPPORTED, "%s: several pieces are not supported", path);
    int ok1, ok2;
    *np = size_prop(*piece, "NumberOfPoints", &ok1);
    *nc = size_prop(*piece, "NumberOfCells", &ok2);
    if (!ok1 || !ok2)
        return vv_error_set(VV_ERR_FORMAT, "%s: Piece without NumberOfPoints / NumberOfCells",
                            path);
    if (*np > VV_GRID_MAX_POINTS || *nc > VV_GRID_MAX_CELLS)
        return vv_error_set(VV_ERR_LIMIT, "%s: %zu points and %zu cells are over the limits", path,
                            *np, *nc);
    /* sizes can not exceed what the file holds (a compressed byte holds at most ~1000) */
    if ((*np + *nc) > (size_t)size * 1032 + 64)
        return vv_error_set(VV_ERR_FORMAT, "%s: %zu points and %zu cells cannot fit in %llu bytes",
                            path, *np, *nc, (unsigned long long)size);
    return VV_OK;
}

/* The grid of the Piece: points, connectivity, offsets and types. */
static vv_status
vtu_grid(vtu *v, xmlNode *piece, size_t np, size_t nc, vv_grid **out) {
    const char *path = v->path;
    double *pts = NULL, *conn = NULL, *offs = NULL, *types = NULL;
    vv_grid *g = NULL;
    vv_status s;
    xmlNode *pa = child(child(piece, "Points"), "DataArray");
    xmlNode *cells = child(piece, "Cells");
    xmlNode *ca = named_array(cells, "connectivity"), *oa = named_array(cells, "offsets"),
            *ta = named_array(cells, "types");
    if (!pa || !ca || !oa || !ta) {
        s = vv_error_set(VV_ERR_FORMAT,
                         "%s: Points or Cells (connectivity, offsets, types) missing", path);
        goto done;
    }
    if ((s = data_array(v, pa, np, 3, NULL, &pts)) != VV_OK ||
        (s = data_array(v, oa, nc, 1, NULL, &offs)) != VV_OK ||
        (s = data_array(v, ta, nc, 1, NULL, &types)) != VV_OK)
        goto done;
    const size_t nconn = nc ? (size_t)(offs[nc - 1] >= 0 ? offs[nc - 1] : 0) : 0;
    if (nc && (!(offs[nc - 1] >= 0) || offs[nc - 1] > (double)nc * 64)) {
        s = vv_error_set(VV_ERR_FORMAT, "%s: cell offsets end at %g", path, offs[nc - 1]);
        goto done;
    }
    if ((s = data_array(v, ca, nconn, 1, NULL, &conn)) != VV_OK ||
        (s = vv_grid_new(&g, VV_GRID_UNSTRUCTURED)) != VV_OK ||
        (s = vv_grid_alloc(g, np, nc, nconn)) != VV_OK)
        goto done;
    memcpy(g->points, pts, 3 * np * sizeof *pts);
    for (size_t i = 0; i < nconn; i++) {
        if (!(conn[i] >= 0) || conn[i] >= (double)np) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: connectivity[%zu] = %g but there are %zu points",
                             path, i, conn[i], np);
            goto done;
        }
        g->connectivity[i] = (uint32_t)conn[i];
    }
    for (size_t i = 0; i < nc; i++) {
        const double o = offs[i], prev = i ? offs[i - 1] : 0;
        if (!(o >= prev) || o > (double)nconn) {
            s = vv_error_set(VV_ERR_FORMAT, "%s: cell %zu: offset %g after %g", path, i, o, prev);
            goto done;
        }
        g->cell_offsets[i + 1] = (size_t)o;
        g->cell_types[i] = (uint8_t)(types[i] >= 0 && types[i] < 256 ? types[i] : 255);
    }
done:
    free(pts);
    free(conn);
    free(offs);
    free(types);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    *out = g;
    return VV_OK;
}

/* Every DataArray of PointData and CellData as a field. */
static vv_status
vtu_fields(vtu *v, xmlNode *piece, vv_grid *g) {
    for (int sec = 0; sec < 2; sec++) {
        xmlNode *pd = child(piece, sec ? "CellData" : "PointData");
        for (xmlNode *c = pd ? pd->children : NULL; c; c = c->next) {
            if (!is_elem(c, "DataArray"))
                continue;
            int ncomp = 1;
            double *vals = NULL;
            char *nm = prop(c, "Name");
            vv_status s = data_array(v, c, sec ? g->n_cells : g->n_points, 0, &ncomp, &vals);
            vv_grid_field *f = NULL;
            if (s == VV_OK)
                s = vv_grid_add_field(g, nm ? nm : "field", sec, ncomp, &f);
            xmlFree(nm);
            for (size_t i = 0; s == VV_OK && i < f->n_tuples * (size_t)ncomp; i++)
                f->values[i] = (float)vals[i];
            free(vals);
            if (s != VV_OK)
                return s;
        }
    }
    return VV_OK;
}

vv_status
vv_grid_read_vtu(vv_grid **out, const char *path) {
    *out = NULL;
    unsigned char *data = NULL, *xml = NULL;
    uint64_t size = 0;
    vv_status s = vv_read_file(path, VTU_FILE_MAX, &data, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s", path);
    vtu v = {path, 0, 0, 0, NULL, 0, 0};
    xmlDoc *doc = NULL;
    xmlNode *piece = NULL, *grid = NULL;
    vv_grid *g = NULL;
    size_t np = 0, nc = 0;
    if ((s = vv_vtkxml_open(&v, data, size, "UnstructuredGrid", &doc, &xml, &grid)) == VV_OK &&
        (s = vtu_piece(&v, grid, size, &piece, &np, &nc)) == VV_OK &&
        (s = vtu_grid(&v, piece, np, nc, &g)) == VV_OK)
        s = vtu_fields(&v, piece, g);
    if (doc)
        xmlFreeDoc(doc);
    if (xml && xml != data)
        free(xml);
    free(data);
    if (s != VV_OK) {
        vv_grid_free(g);
        return s;
    }
    return vv_grid_finish(g, path, out);
}

/* ---- the format record ------------------------------------------------------ */

static int
vtu_looks_like(const vv_format_probe *p, int deep) {
    return !deep && strstr(p->text, "<VTKFile") && strstr(p->text, "UnstructuredGrid");
}

static const char *const vtu_extensions[] = {"vtu", NULL};

const vv_format_record vv_format_vtu = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vtu",
    .title = ".vtu",
    .extensions = vtu_extensions,
    .doc = "VTK XML UnstructuredGrid through libxml2: inline or appended, base64, zlib",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .holds = VV_DATA_GRID,
    .looks_like = vtu_looks_like,
    .read_grid = vv_grid_read_vtu,
};
