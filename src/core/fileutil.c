/* Atomic output files, whole-file reads, paths, byte order. */
#define _GNU_SOURCE /* O_TMPFILE, AT_EMPTY_PATH */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/internal.h"

char *
vv_strdup(const char *s) {
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

static vv_status
atomic_open_failed(vv_atomic_file *af, const char *path, int err) {
    vv_status s = vv_error_set(VV_ERR_IO, "%s: cannot create: %s", path, strerror(err));
    free(af->path);
    free(af->tmp_path);
    memset(af, 0, sizeof *af);
    af->fd = -1;
    return s;
}

/* Room for what vv_tmp_name adds to a path (".tmp-" and the owner). */
#define TMP_SUFFIX_MAX 64

/* A name beside the target for the temporary file, naming this process
 * (vv_tmp_name). */
static void
tmp_name(const vv_atomic_file *af, size_t cap, int attempt) {
    (void)vv_tmp_name(af->tmp_path, cap, af->path, (long)getpid(),
                      (unsigned)attempt ^ (unsigned)(uintptr_t)af);
}

vv_status
vv_atomic_file_open(vv_atomic_file *af, const char *path) {
    memset(af, 0, sizeof *af);
    af->fd = -1;
    size_t n = strlen(path);
    af->path = vv_strdup(path);
    af->tmp_path = malloc(n + TMP_SUFFIX_MAX);
    if (!af->path || !af->tmp_path) {
        free(af->path);
        free(af->tmp_path);
        memset(af, 0, sizeof *af);
        af->fd = -1;
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    af->tmp_path[0] = '\0';
    /* the named temporaries of writers of this target that were killed */
    (void)vv_tmp_sweep(path);
    /* First choice: an unnamed file in the target's folder (O_TMPFILE), given
     * a name only at commit, so a process killed mid-write leaves nothing
     * behind. Where the file system cannot (EOPNOTSUPP, EISDIR on old
     * kernels), a named temporary beside the target. Both get the usual
     * permissions: 0666 less the umask, applied by the kernel. */
    int fd = -1;
#ifdef O_TMPFILE
    {
        const char *slash = strrchr(path, '/');
        char *dir = slash ? vv_strdup(path) : NULL;
        if (slash && !dir) {
            free(af->path);
            free(af->tmp_path);
            memset(af, 0, sizeof *af);
            af->fd = -1;
            return vv_error_set(VV_ERR_NOMEM, "out of memory");
        }
        if (dir)
            dir[slash == path ? 1 : (size_t)(slash - path)] = '\0';
        fd = open(dir ? dir : ".", O_TMPFILE | O_RDWR | O_CLOEXEC, 0666);
        free(dir);
        if (fd >= 0)
            af->anonymous = 1;
        else if (errno == ENOENT || errno == ENOTDIR || errno == EACCES || errno == EROFS ||
                 errno == ENOSPC || errno == EDQUOT)
            return atomic_open_failed(af, path, errno);
    }
#endif
    for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
        tmp_name(af, n + TMP_SUFFIX_MAX, attempt);
        fd = open(af->tmp_path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0 && errno != EEXIST)
            break;
    }
    if (fd < 0)
        return atomic_open_failed(af, path, errno);
    af->fp = fdopen(fd, "wb");
    if (!af->fp) {
        int err = errno;
        close(fd);
        if (!af->anonymous)
            unlink(af->tmp_path);
        free(af->path);
        free(af->tmp_path);
        memset(af, 0, sizeof *af);
        af->fd = -1;
        return vv_error_set(VV_ERR_IO, "%s: cannot open: %s", path, strerror(err));
    }
    af->fd = fd;
    return VV_OK;
}

/* Gives the unnamed file a temporary name beside the target, for rename. */
static int
link_anonymous(vv_atomic_file *af) {
    size_t cap = strlen(af->path) + TMP_SUFFIX_MAX;
    char proc[64];
    snprintf(proc, sizeof proc, "/proc/self/fd/%d", af->fd);
    for (int attempt = 0; attempt < 100; attempt++) {
        tmp_name(af, cap, attempt);
        if (linkat(AT_FDCWD, proc, AT_FDCWD, af->tmp_path, AT_SYMLINK_FOLLOW) == 0)
            return 0;
        if (errno == EEXIST)
            continue;
        /* no /proc: linking the descriptor itself needs CAP_DAC_READ_SEARCH */
        if (linkat(af->fd, "", AT_FDCWD, af->tmp_path, AT_EMPTY_PATH) == 0)
            return 0;
        if (errno != EEXIST)
            return -1;
    }
    return -1;
}

vv_status
vv_atomic_file_commit(vv_atomic_file *af) {
    if (!af->fp)
        return vv_error_set(VV_ERR_IO, "atomic file not open");
    int bad = ferror(af->fp) || fflush(af->fp) != 0 || fsync(af->fd) != 0;
    int err = errno;
    if (!bad && af->anonymous && link_anonymous(af) != 0) {
        vv_status s = vv_error_set(VV_ERR_IO, "%s: cannot name the written file: %s", af->path,
                                   strerror(errno));
        vv_atomic_file_abort(af);
        return s;
    }
    af->anonymous = 0; /* from here on it has a name to remove on failure */
    if (fclose(af->fp) != 0 && !bad) {
        bad = 1;
        err = errno;
    }
    af->fp = NULL;
    af->fd = -1;
    if (bad) {
        vv_status s = vv_error_set(VV_ERR_IO, "%s: write failed: %s", af->path, strerror(err));
        vv_atomic_file_abort(af);
        return s;
    }
    if (rename(af->tmp_path, af->path) != 0) {
        vv_status s = vv_error_set(VV_ERR_IO, "%s: cannot rename temporary file: %s", af->path,
                                   strerror(errno));
        vv_atomic_file_abort(af);
        return s;
    }
    free(af->path);
    free(af->tmp_path);
    memset(af, 0, sizeof *af);
    af->fd = -1;
    return VV_OK;
}

void
vv_atomic_file_abort(vv_atomic_file *af) {
    if (af->fp)
        fclose(af->fp);
    if (af->tmp_path && !af->anonymous && af->tmp_path[0])
        unlink(af->tmp_path);
    free(af->path);
    free(af->tmp_path);
    memset(af, 0, sizeof *af);
    af->fd = -1;
}

vv_status
vv_read_file(const char *path, uint64_t max_bytes, unsigned char **data, uint64_t *size) {
    *data = NULL;
    *size = 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return vv_error_set(VV_ERR_IO, "%s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        return vv_error_set(VV_ERR_IO, "%s: not a regular file", path);
    }
    if ((uint64_t)st.st_size > max_bytes) {
        fclose(f);
        return vv_error_set(VV_ERR_LIMIT, "%s: file of %lld bytes is over the limit of %llu", path,
                            (long long)st.st_size, (unsigned long long)max_bytes);
    }
    /* the whole file is held: it counts against the memory budget (the
       grid readers took files of up to 4 GiB whatever the budget) */
    vv_status sb = vv_memory_budget_check((uint64_t)st.st_size + 1, path);
    if (sb != VV_OK) {
        fclose(f);
        return sb;
    }
    size_t n = (size_t)st.st_size;
    unsigned char *buf = malloc(n + 1);
    if (!buf) {
        fclose(f);
        return vv_error_set(VV_ERR_NOMEM, "%s: out of memory for %zu bytes", path, n);
    }
    if (n && fread(buf, 1, n, f) != n) {
        free(buf);
        fclose(f);
        return vv_error_set(VV_ERR_IO, "%s: read failed", path);
    }
    fclose(f);
    buf[n] = 0;
    *data = buf;
    *size = n;
    return VV_OK;
}

vv_status
vv_open_regular(const char *path, FILE **fp, uint64_t *size) {
    *fp = fopen(path, "rb");
    if (!*fp)
        return vv_error_set(VV_ERR_IO, "cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fileno(*fp), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(*fp);
        *fp = NULL;
        return vv_error_set(VV_ERR_IO, "not a regular file");
    }
    *size = (uint64_t)st.st_size;
    return VV_OK;
}

const char *
vv_path_basename(const char *path) {
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

char *
vv_path_join_dir(const char *base_file, const char *rel) {
    if (rel[0] == '/')
        return vv_strdup(rel);
    const char *slash = strrchr(base_file, '/');
    if (!slash)
        return vv_strdup(rel);
    size_t dn = (size_t)(slash - base_file) + 1;
    size_t rn = strlen(rel);
    char *out = malloc(dn + rn + 1);
    if (!out)
        return NULL;
    memcpy(out, base_file, dn);
    memcpy(out + dn, rel, rn + 1);
    return out;
}

vv_status
vv_detached_path(const char *header, const char *rel, char **out, uint64_t *size) {
    if (out)
        *out = NULL;
    if (!rel[0])
        return vv_error_set(VV_ERR_FORMAT, "empty data file name");
    if (rel[0] == '/')
        return vv_error_set(VV_ERR_FORMAT,
                            "data file '%s' refused: an absolute path (data files are named "
                            "relative to the header's folder)",
                            rel);
    for (const char *c = rel; *c;) {
        size_t n = strcspn(c, "/");
        if (n == 2 && c[0] == '.' && c[1] == '.')
            return vv_error_set(VV_ERR_FORMAT,
                                "data file '%s' refused: '..' leaves the header's folder", rel);
        c += n;
        while (*c == '/')
            c++;
    }
    char *path = vv_path_join_dir(header, rel);
    if (!path)
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    struct stat st;
    if (stat(path, &st) != 0) {
        int e = errno;
        free(path);
        return vv_error_set(VV_ERR_IO, "cannot open data file '%s': %s", rel, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        free(path);
        return vv_error_set(VV_ERR_FORMAT, "data file '%s' refused: %s, not a regular file", rel,
                            S_ISDIR(st.st_mode)                          ? "a folder"
                            : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                            : S_ISFIFO(st.st_mode)                       ? "a FIFO"
                                                                         : "a special file");
    }
    /* a symbolic link may still lead out of the folder: compare the real paths */
    const char *slash = strrchr(header, '/');
    char *dir = slash ? strndup(header, (size_t)(slash - header) + 1) : vv_strdup(".");
    char *rdir = dir ? realpath(dir, NULL) : NULL;
    char *rfile = realpath(path, NULL);
    int inside = 0;
    if (rdir && rfile) {
        size_t n = strlen(rdir);
        inside = strncmp(rfile, rdir, n) == 0 && (rfile[n] == '/' || (n == 1 && rdir[0] == '/'));
    }
    free(dir);
    free(rdir);
    free(rfile);
    if (!inside) {
        free(path);
        return vv_error_set(VV_ERR_FORMAT,
                            "data file '%s' refused: it resolves outside the header's folder", rel);
    }
    if (size)
        *size = (uint64_t)st.st_size;
    if (out)
        *out = path;
    else
        free(path);
    return VV_OK;
}

int
vv_host_is_little_endian(void) {
    const uint16_t one = 1;
    return *(const uint8_t *)&one == 1;
}

void
vv_byteswap(void *data, uint64_t count, size_t size) {
    uint8_t *p = data;
    if (size < 2)
        return;
    for (uint64_t e = 0; e < count; e++, p += size) {
        for (size_t a = 0, b = size - 1; a < b; a++, b--) {
            uint8_t t = p[a];
            p[a] = p[b];
            p[b] = t;
        }
    }
}
