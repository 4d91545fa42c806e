/*
 * Mesh files through Assimp: every format Assimp reads (OBJ, PLY, STL, OFF,
 * glTF, ...) into a vv_mesh, and binary PLY, OBJ and binary STL written by
 * Assimp's exporters (see include/volvis/mesh.h).
 */
#include <assimp/cexport.h>
#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/prescan.h"
#include "volvis/io.h"
#include "volvis/mesh.h"
#include "volvis/sys/format.h"

/* Mesh files larger than this are refused before Assimp reads them. */
#define MESH_MAX_FILE_BYTES ((uint64_t)8 << 30)

/* ---- OFF validation ------------------------------------------------------ */

/* The next line of @p t (from *pos) that is neither blank nor a comment,
 * NUL-terminated in place (comments cut); NULL at the end. */
static char *
off_next_line(char *t, size_t n, size_t *pos) {
    while (*pos < n) {
        char *line = t + *pos;
        char *nl = memchr(line, '\n', n - *pos);
        size_t len = nl ? (size_t)(nl - line) : n - *pos;
        *pos += len + (nl ? 1 : 0);
        line[len] = '\0';
        char *hash = strchr(line, '#');
        if (hash)
            *hash = '\0';
        char *c = line;
        while (isspace((unsigned char)*c))
            c++;
        if (*c)
            return c;
    }
    return NULL;
}

/*
 * Checks an OFF file before Assimp reads it (Debian's Assimp is built with
 * assertions, and its OFF loader asserts on a header without faces or a face
 * without indices): the header keyword ([ST][C][N][4]OFF, text only), the
 * vertex and face counts (at least 3 and 1, no more than the file's size
 * allows), every vertex line (3 numbers), every face (3 or more indices,
 * each a vertex).
 */
static vv_status
off_validate(const char *path, uint64_t size) {
    unsigned char *data = NULL;
    uint64_t n = 0;
    vv_status s = vv_read_file(path, size + 1, &data, &n);
    if (s != VV_OK)
        return s;
    char *t = (char *)data;
    if (memchr(t, '\0', (size_t)n)) {
        free(data);
        return vv_error_set(VV_ERR_UNSUPPORTED, "OFF: binary OFF is not supported");
    }
    size_t pos = 0;
    char *line = off_next_line(t, (size_t)n, &pos);
    char kw[32] = "";
    char *rest = line;
    if (line) {
        size_t k = strspn(line, "STCN4nOF");
        if (k < sizeof kw) {
            memcpy(kw, line, k);
            kw[k] = '\0';
        }
        rest = line + k;
    }
    size_t kl = strlen(kw);
    if (kl < 3 || strcmp(kw + kl - 3, "OFF") != 0) {
        free(data);
        return vv_error_set(VV_ERR_FORMAT, "OFF: no OFF keyword on the first line");
    }
    while (isspace((unsigned char)*rest))
        rest++;
    if (!strncmp(rest, "BINARY", 6)) {
        free(data);
        return vv_error_set(VV_ERR_UNSUPPORTED, "OFF: binary OFF is not supported");
    }
    if (!*rest)
        rest = off_next_line(t, (size_t)n, &pos);
    long long nv = -1, nf = -1;
    if (!rest || sscanf(rest, "%lld %lld", &nv, &nf) != 2) {
        free(data);
        return vv_error_set(VV_ERR_FORMAT, "OFF: the header has no vertex and face counts");
    }
    if (nv < 3 || nf < 1 || (uint64_t)nv > n / 6 || (uint64_t)nf > n / 6) {
        free(data);
        return vv_error_set(VV_ERR_FORMAT,
                            "OFF: %lld vertices and %lld faces (at least 3 and 1, and no more "
                            "than a file of %llu bytes holds)",
                            nv, nf, (unsigned long long)n);
    }
    for (long long i = 0; i < nv; i++) {
        double x, y, z;
        line = off_next_line(t, (size_t)n, &pos);
        if (!line || sscanf(line, "%lf %lf %lf", &x, &y, &z) != 3) {
            free(data);
            return vv_error_set(VV_ERR_FORMAT, "OFF: vertex %lld: expected 3 numbers", i);
        }
    }
    for (long long i = 0; i < nf; i++) {
        line = off_next_line(t, (size_t)n, &pos);
        char *c = line, *e = NULL;
        long long k = line ? strtoll(c, &e, 10) : -1;
        if (!line || e == c || k < 3 || k > nv) {
            free(data);
            return vv_error_set(VV_ERR_FORMAT,
                                "OFF: face %lld: %s (a face has 3 or more vertex indices)", i,
                                line ? "too few indices" : "missing");
        }
        c = e;
        for (long long j = 0; j < k; j++) {
            long long idx = strtoll(c, &e, 10);
            if (e == c || idx < 0 || idx >= nv) {
                free(data);
                return vv_error_set(VV_ERR_FORMAT, "OFF: face %lld: index %lld %s (%lld vertices)",
                                    i, j, e == c ? "is missing" : "is out of range", nv);
            }
            c = e;
        }
    }
    free(data);
    return VV_OK;
}

/* 1 when @p path is an OFF file by name or by its first bytes. */
static int
is_off(const char *path) {
    size_t n = strlen(path);
    if (n >= 4 && !strcasecmp(path + n - 4, ".off"))
        return 1;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char b[8] = {0};
    size_t got = fread(b, 1, sizeof b - 1, f);
    fclose(f);
    b[got] = '\0';
    size_t k = strspn(b, "STCN4n");
    return !strncmp(b + k, "OFF", 3);
}

/* ---- STL validation ------------------------------------------------------ */

/* A token of an ASCII STL: where it starts and its length. */
typedef struct stl_tok {
    const char *p;
    size_t n;
} stl_tok;

/* The next whitespace-separated token of @p t from *pos; n is 0 at the end. */
static stl_tok
stl_token(const char *t, size_t n, size_t *pos) {
    stl_tok k = {NULL, 0};
    while (*pos < n && isspace((unsigned char)t[*pos]))
        (*pos)++;
    k.p = t + *pos;
    while (*pos < n && !isspace((unsigned char)t[*pos]))
        (*pos)++;
    k.n = (size_t)(t + *pos - k.p);
    return k;
}

static int
stl_is(stl_tok k, const char *word) {
    return k.n == strlen(word) && !memcmp(k.p, word, k.n);
}

static int
stl_expect(const char *t, size_t n, size_t *pos, const char *word) {
    return stl_is(stl_token(t, n, pos), word);
}

static int
stl_numbers(const char *t, size_t n, size_t *pos, int k) {
    for (int i = 0; i < k; i++) {
        stl_tok tok = stl_token(t, n, pos);
        char buf[64], *e = NULL;
        if (tok.n == 0 || tok.n >= sizeof buf)
            return 0;
        memcpy(buf, tok.p, tok.n);
        buf[tok.n] = '\0';
        strtod(buf, &e);
        if (e == buf || *e)
            return 0;
    }
    return 1;
}

/* Moves *pos to the end of the current line. */
static void
stl_skip_line(const char *t, size_t n, size_t *pos) {
    while (*pos < n && t[*pos] != '\n')
        (*pos)++;
}

/*
 * Checks an STL file before Assimp reads it (Assimp 5.2 leaks the mesh and
 * node it was building when an ASCII STL is malformed): a binary STL must
 * hold the 50 bytes of each of its (at least one) triangles; an ASCII one
 * ("solid" first, and not the size of a binary one) must be a sequence of
 * "facet normal n n n / outer loop / vertex x y z (three times) / endloop /
 * endfacet" blocks, each solid closed by "endsolid".
 */
static vv_status
stl_validate(const char *path, uint64_t size) {
    unsigned char *data = NULL;
    uint64_t n = 0;
    vv_status s = vv_read_file(path, size + 1, &data, &n);
    if (s != VV_OK)
        return s;
    uint32_t count = 0;
    if (n >= 84)
        count = (uint32_t)data[80] | (uint32_t)data[81] << 8 | (uint32_t)data[82] << 16 |
                (uint32_t)data[83] << 24;
    int binary = n < 5 || memcmp(data, "solid", 5) != 0 ||
                 (n >= 84 && (uint64_t)84 + (uint64_t)50 * count == n);
    if (binary) {
        if (n < 84 || count == 0 || (uint64_t)84 + (uint64_t)50 * count > n)
            s = vv_error_set(VV_ERR_FORMAT,
                             "STL: a binary file of %llu bytes cannot hold its %u triangles",
                             (unsigned long long)n, count);
        free(data);
        return s;
    }
    const char *t = (const char *)data;
    size_t pos = 0, tn = (size_t)n;
    long facets = 0;
    stl_tok tok = stl_token(t, tn, &pos);
    while (tok.n && s == VV_OK) {
        if (!stl_is(tok, "solid")) {
            s = vv_error_set(VV_ERR_FORMAT, "STL: expected 'solid', got '%.*s'",
                             (int)(tok.n < 32 ? tok.n : 32), tok.p);
            break;
        }
        stl_skip_line(t, tn, &pos); /* the name */
        for (;;) {
            tok = stl_token(t, tn, &pos);
            if (!tok.n) {
                s = vv_error_set(VV_ERR_FORMAT, "STL: no 'endsolid' after facet %ld", facets);
                break;
            }
            if (stl_is(tok, "endsolid")) {
                stl_skip_line(t, tn, &pos);
                break;
            }
            if (!stl_is(tok, "facet") || !stl_expect(t, tn, &pos, "normal") ||
                !stl_numbers(t, tn, &pos, 3) || !stl_expect(t, tn, &pos, "outer") ||
                !stl_expect(t, tn, &pos, "loop")) {
                s = vv_error_set(VV_ERR_FORMAT,
                                 "STL: facet %ld: expected 'facet normal N N N outer loop'",
                                 facets);
                break;
            }
            for (int v = 0; v < 3 && s == VV_OK; v++)
                if (!stl_expect(t, tn, &pos, "vertex") || !stl_numbers(t, tn, &pos, 3))
                    s = vv_error_set(VV_ERR_FORMAT,
                                     "STL: facet %ld: vertex %d: expected 'vertex X Y Z'", facets,
                                     v);
            if (s == VV_OK &&
                (!stl_expect(t, tn, &pos, "endloop") || !stl_expect(t, tn, &pos, "endfacet")))
                s = vv_error_set(VV_ERR_FORMAT, "STL: facet %ld: expected 'endloop endfacet'",
                                 facets);
            if (s != VV_OK)
                break;
            facets++;
        }
        if (s == VV_OK)
            tok = stl_token(t, tn, &pos);
    }
    if (s == VV_OK && facets == 0)
        s = vv_error_set(VV_ERR_FORMAT, "STL: no facets");
    free(data);
    return s;
}

/* 1 when @p path is an STL file by name or starts with "solid". */
static int
is_stl(const char *path) {
    size_t n = strlen(path);
    if (n >= 4 && !strcasecmp(path + n - 4, ".stl"))
        return 1;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char b[6] = {0};
    size_t got = fread(b, 1, 5, f);
    fclose(f);
    return got == 5 && !memcmp(b, "solid", 5);
}

/* ---- PLY header validation ------------------------------------------------ */

/*
 * Checks a PLY header before Assimp reads it (its PLY loader loops forever
 * on some malformed headers): "ply", a "format" line, then only "format",
 * "comment", "obj_info", "element NAME COUNT" and "property ..." lines up to
 * "end_header", all within the first 64 KiB.
 */
static vv_status
ply_validate(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "cannot open");
    char line[1024];
    int n = 0, have_format = 0;
    long read = 0;
    vv_status s = VV_ERR_FORMAT; /* until end_header is seen */
    int decided = 0;
    while (read < 65536 && fgets(line, sizeof line, f)) {
        size_t len = strlen(line);
        read += (long)len;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r' || line[len - 1] == ' '))
            line[--len] = '\0';
        if (n++ == 0) {
            if (strcmp(line, "ply") != 0) {
                s = vv_error_set(VV_ERR_FORMAT, "PLY: the first line is not 'ply'");
                decided = 1;
                break;
            }
            continue;
        }
        if (!strcmp(line, "end_header")) {
            s = have_format ? VV_OK
                            : vv_error_set(VV_ERR_FORMAT, "PLY: no format line in the header");
            decided = 1;
            break;
        }
        long long count;
        char name[256];
        if (!strncmp(line, "format ", 7)) {
            const char *fm = line + 7;
            if (strncmp(fm, "ascii ", 6) && strncmp(fm, "binary_little_endian ", 21) &&
                strncmp(fm, "binary_big_endian ", 18)) {
                s = vv_error_set(VV_ERR_FORMAT, "PLY: unknown format '%.60s'", fm);
                decided = 1;
                break;
            }
            have_format = 1;
        } else if (!strncmp(line, "element ", 8)) {
            if (sscanf(line + 8, "%255s %lld", name, &count) != 2 || count < 0) {
                s = vv_error_set(VV_ERR_FORMAT, "PLY: header line %d: bad element line", n);
                decided = 1;
                break;
            }
        } else if (strncmp(line, "property ", 9) && strncmp(line, "comment", 7) &&
                   strncmp(line, "obj_info", 8) && line[0] != '\0') {
            s = vv_error_set(VV_ERR_FORMAT, "PLY: header line %d: unknown keyword in '%.40s'", n,
                             line);
            decided = 1;
            break;
        }
    }
    fclose(f);
    if (!decided)
        s = vv_error_set(VV_ERR_FORMAT, "PLY: no end_header line in the first 64 KiB");
    return s;
}

/* 1 when @p path ends in .ply or starts with "ply". */
static int
is_ply(const char *path) {
    size_t n = strlen(path);
    if (n >= 4 && !strcasecmp(path + n - 4, ".ply"))
        return 1;
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char b[5] = {0};
    size_t got = fread(b, 1, 4, f);
    fclose(f);
    return got >= 3 && !memcmp(b, "ply", 3); /* Assimp takes it for PLY on these three bytes */
}

vv_status
vv_mesh_prescan(const char *path) {
    const char *name = vv_path_basename(path);
    FILE *fp = NULL;
    uint64_t size = 0;
    vv_status s = vv_open_regular(path, &fp, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "mesh: %s", name);
    fclose(fp);
    if (size > MESH_MAX_FILE_BYTES)
        return vv_error_set(VV_ERR_LIMIT, "mesh: %s: %llu bytes (at most %llu)", name,
                            (unsigned long long)size, (unsigned long long)MESH_MAX_FILE_BYTES);
    if (size == 0)
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: empty file", name);
    if (is_off(path) && (s = off_validate(path, size)) != VV_OK)
        return vv_error_prefix(s, "mesh: %s", name);
    if (is_stl(path) && (s = stl_validate(path, size)) != VV_OK)
        return vv_error_prefix(s, "mesh: %s", name);
    if (is_ply(path) && (s = ply_validate(path)) != VV_OK)
        return vv_error_prefix(s, "mesh: %s", name);
    return VV_OK;
}

/* The mesh row's read: our own checks (vv_mesh_prescan), then Assimp. */
static vv_status
mesh_read_record(vv_mesh **out, const char *path) {
    *out = NULL;
    const char *name = vv_path_basename(path);
    vv_status s = vv_mesh_prescan(path);
    if (s != VV_OK)
        return s;

    /* Drop every attribute but positions before joining vertices, so facet
     * normals (STL) or texture seams do not split a closed surface; normals
     * are recomputed from the shared vertices. */
    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props)
        return vv_error_set(VV_ERR_NOMEM, "mesh: %s: out of memory", name);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_RVC_FLAGS,
                               aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                   aiComponent_COLORS | aiComponent_TEXCOORDS |
                                   aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                   aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS |
                                   aiComponent_MATERIALS);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE,
                               aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    unsigned flags = aiProcess_RemoveComponent | aiProcess_Triangulate |
                     aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                     aiProcess_SortByPType | aiProcess_FindDegenerates;
    /* Assimp's assertions (on in Debian's build) end the process: in
     * volvis-reader that is one line of error in the parent */
    const struct aiScene *sc = aiImportFileExWithProperties(path, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (!sc) {
        const char *why = aiGetErrorString();
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: %s", name, why && *why ? why : "unreadable");
    }
    size_t nv = 0, nt = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        nv += am->mNumVertices;
        nt += am->mNumFaces;
    }
    if (nt == 0) {
        aiReleaseImport(sc);
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: no triangles", name);
    }
    vv_mesh *m = NULL;
    if ((s = vv_mesh_new(&m)) != VV_OK || (s = vv_mesh_reserve(m, nv, nt)) != VV_OK) {
        aiReleaseImport(sc);
        vv_mesh_free(m);
        return vv_error_prefix(s, "mesh: %s", name);
    }
    for (unsigned i = 0; i < sc->mNumMeshes && s == VV_OK; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        uint32_t base = (uint32_t)m->n_vertices;
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            m->positions[3 * m->n_vertices] = p->x;
            m->positions[3 * m->n_vertices + 1] = p->y;
            m->positions[3 * m->n_vertices + 2] = p->z;
            m->n_vertices++;
        }
        for (unsigned f = 0; f < am->mNumFaces && s == VV_OK; f++) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3)
                continue;
            s = vv_mesh_add_triangle(m, base + face->mIndices[0], base + face->mIndices[1],
                                     base + face->mIndices[2]);
        }
    }
    aiReleaseImport(sc);
    if (s == VV_OK && m->n_triangles == 0)
        s = vv_error_set(VV_ERR_FORMAT, "mesh: %s: no triangles", name);
    if (s == VV_OK)
        s = vv_mesh_compute_normals(m);
    if (s != VV_OK) {
        vv_mesh_free(m);
        return vv_error_prefix(s, "mesh: %s", name);
    }
    *out = m;
    return VV_OK;
}

/* The Assimp exporter id for a file name's extension, or NULL. */
static const char *
export_format(const char *path) {
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return NULL;
    if (strcasecmp(dot, ".ply") == 0)
        return "plyb";
    if (strcasecmp(dot, ".obj") == 0)
        return "objnomtl";
    if (strcasecmp(dot, ".stl") == 0)
        return "stlb";
    if (strcasecmp(dot, ".glb") == 0)
        return "glb2"; /* glTF 2.0 binary */
    return NULL;
}

vv_status
vv_mesh_save(const vv_mesh *m, const char *path) {
    if (!m || !path)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL argument");
    const char *name = vv_path_basename(path);
    if (vv_format_path_has_ext(path, "vtp"))
        return vv_vtp_write(m, path, NULL);
    const char *fmt = export_format(path);
    if (!fmt)
        return vv_error_set(VV_ERR_INVALID,
                            "mesh: %s: unknown extension (use .ply, .obj, .stl, .glb or .vtp)",
                            name);
    if (m->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh: %s: the mesh has no triangles", name);
    if (m->n_vertices > UINT32_MAX || m->n_triangles > UINT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "mesh: %s: too large for the exporter", name);

    /* A one-mesh scene in Assimp's structures, owned here (not by Assimp). */
    struct aiScene sc;
    struct aiNode root;
    struct aiMesh am;
    struct aiMaterial mat;
    memset(&sc, 0, sizeof sc);
    memset(&root, 0, sizeof root);
    memset(&am, 0, sizeof am);
    memset(&mat, 0, sizeof mat);
    struct aiMesh *meshes[1] = {&am};
    struct aiMaterial *mats[1] = {&mat};
    unsigned mesh_index = 0;
    struct aiMaterialProperty *no_props[1] = {NULL};
    mat.mProperties = no_props;
    mat.mNumAllocated = 1;
    root.mName.length = 4;
    memcpy(root.mName.data, "root", 5);
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            (&root.mTransformation.a1)[4 * r + c] = r == c ? 1.0f : 0.0f;
    root.mNumMeshes = 1;
    root.mMeshes = &mesh_index;
    sc.mRootNode = &root;
    sc.mNumMeshes = 1;
    sc.mMeshes = meshes;
    sc.mNumMaterials = 1;
    sc.mMaterials = mats;

    am.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    am.mNumVertices = (unsigned)m->n_vertices;
    am.mNumFaces = (unsigned)m->n_triangles;
    am.mVertices = malloc(m->n_vertices * sizeof *am.mVertices);
    am.mNormals = m->normals ? malloc(m->n_vertices * sizeof *am.mNormals) : NULL;
    am.mFaces = malloc(m->n_triangles * sizeof *am.mFaces);
    int ok = am.mVertices && am.mFaces && (!m->normals || am.mNormals);
    if (ok) {
        for (size_t i = 0; i < m->n_vertices; i++) {
            am.mVertices[i].x = m->positions[3 * i];
            am.mVertices[i].y = m->positions[3 * i + 1];
            am.mVertices[i].z = m->positions[3 * i + 2];
            if (m->normals) {
                am.mNormals[i].x = m->normals[3 * i];
                am.mNormals[i].y = m->normals[3 * i + 1];
                am.mNormals[i].z = m->normals[3 * i + 2];
            }
        }
        for (size_t t = 0; t < m->n_triangles; t++) {
            am.mFaces[t].mNumIndices = 3;
            am.mFaces[t].mIndices = m->triangles + 3 * t;
        }
    }
    vv_status s = VV_OK;
    if (!ok) {
        s = vv_error_set(VV_ERR_NOMEM, "mesh: %s: out of memory", name);
    } else {
        /* exported to memory and written through an atomic file, so a full
         * disk or a killed process never leaves a partial mesh (Assimp's own
         * file writer does not check its writes) */
        const struct aiExportDataBlob *blob = aiExportSceneToBlob(&sc, fmt, 0);
        if (!blob) {
            const char *why = aiGetErrorString();
            s = vv_error_set(VV_ERR_IO, "mesh: %s: %s", name,
                             why && *why ? why : "the exporter failed");
        } else {
            vv_atomic_file af;
            s = vv_atomic_file_open(&af, path);
            if (s != VV_OK) {
                s = vv_error_prefix(s, "mesh");
            } else if (fwrite(blob->data, 1, blob->size, af.fp) != blob->size) {
                s = vv_error_set(VV_ERR_IO, "mesh: %s: write failed: %s", name, strerror(errno));
                vv_atomic_file_abort(&af);
            } else if ((s = vv_atomic_file_commit(&af)) != VV_OK) {
                s = vv_error_prefix(s, "mesh");
            }
            aiReleaseExportBlob(blob);
        }
    }
    free(am.mVertices);
    free(am.mNormals);
    free(am.mFaces);
    return s;
}

/* ---- the format record ------------------------------------------------------ */

static const char *const mesh_extensions[] = {"obj",  "ply", "stl", "off", "glb",
                                              "gltf", "dae", "fbx", "3ds", NULL};

/* Meshes have no common signature: a mesh is a file of a mesh extension
 * that no other row claimed (Assimp decides when it reads it). */
static int
mesh_looks_like(const vv_format_probe *p, int deep) {
    if (!deep || p->is_dir)
        return 0;
    for (const char *const *e = mesh_extensions; *e; e++)
        if (vv_format_path_has_ext(p->path, *e))
            return 1;
    return 0;
}

const vv_format_record vv_format_mesh = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "mesh",
    .title = "mesh",
    .extensions = mesh_extensions,
    .doc = "triangle meshes through Assimp (OBJ, PLY, STL, OFF, glTF, COLLADA, FBX, 3DS, ...)",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .holds = VV_DATA_MESH,
    .looks_like = mesh_looks_like,
    .read_mesh = mesh_read_record,
};
