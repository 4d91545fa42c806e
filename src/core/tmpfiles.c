/*
 * Temporaries beside a target, named by their writer: every atomic writer
 * (vv_atomic_file, the OME-Zarr store writer, the .vvb writer) writes into
 * "<target>.tmp-<host>-<pid>-<start>-<random>" and renames it over the
 * target, so a writer killed mid-write (SIGKILL, a crash, the machine
 * stopped) leaves a temporary whose name says who made it, and the next
 * writer of the same target removes it once that process is gone. A
 * temporary of a writer still running is never touched: two writers of
 * one target keep each other's.
 */
#define _GNU_SOURCE /* O_NOFOLLOW, O_DIRECTORY, fdopendir */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core/internal.h"

/* Folders nested deeper than this inside a temporary are left (a store
 * holds level/c/z/y/x: a handful). */
#define TMP_TREE_DEPTH 32
/* Passes over a folder while removing it: entries removed during readdir
 * may hide others on some file systems; a later pass finds them. */
#define TMP_TREE_PASSES 4

/* FNV-1a over @p s, continuing from @p h. */
static uint32_t
fnv1a(uint32_t h, const char *s) {
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 16777619u;
    }
    return h;
}

/* Who may judge a temporary's writer alive: the host's name and the PID
 * namespace (process ids mean something only there), hashed. A temporary
 * made elsewhere (another machine on a shared file system, another
 * container) carries another tag and is left alone. */
static uint32_t
host_tag(void) {
    char host[256] = "", ns[64] = "";
    if (gethostname(host, sizeof host - 1) != 0)
        host[0] = '\0';
    ssize_t n = readlink("/proc/self/ns/pid", ns, sizeof ns - 1);
    ns[n > 0 ? n : 0] = '\0';
    return fnv1a(fnv1a(2166136261u, host), ns);
}

/* Process @p pid's state letter and start time (clock ticks after boot,
 * field 22 of /proc/PID/stat); 0 when it cannot be read (no /proc, gone). */
static int
proc_stat(long pid, char *state, unsigned long long *start) {
    char path[64], buf[1024];
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    ssize_t n = read(fd, buf, sizeof buf - 1);
    close(fd);
    if (n <= 0)
        return 0;
    buf[n] = '\0';
    /* the command name (field 2) may hold spaces and parentheses: fields
     * 3 on follow the last ')' */
    const char *p = strrchr(buf, ')');
    if (!p || p[1] != ' ' || !p[2])
        return 0;
    *state = p[2];
    p += 3;
    for (int field = 4; field <= 22; field++) { /* skip to field 22 */
        while (*p == ' ')
            p++;
        if (field == 22)
            break;
        while (*p && *p != ' ')
            p++;
    }
    char *end;
    errno = 0;
    *start = strtoull(p, &end, 10);
    return end != p && errno == 0;
}

/* 1 while the writer @p pid that started at @p start (0: not known) runs:
 * a process of that id exists (kill 0 succeeds or is refused), it is not a
 * zombie, and its start time is the one recorded (else the id was given to
 * another process since). */
static int
writer_alive(long pid, unsigned long long start) {
    if (kill((pid_t)pid, 0) != 0 && errno == ESRCH)
        return 0;
    char state = 0;
    unsigned long long now = 0;
    if (!proc_stat(pid, &state, &now))
        return 1; /* no /proc: the id alone */
    if (state == 'Z' || state == 'X')
        return 0;
    return start == 0 || now == start;
}

int
vv_tmp_name(char *buf, size_t cap, const char *path, long pid, unsigned attempt) {
    char state;
    unsigned long long start = 0;
    if (!proc_stat(pid, &state, &start))
        start = 0;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    unsigned r = (unsigned)pid * 2654435761u ^ (unsigned)ts.tv_nsec ^
                 (unsigned)(uintptr_t)buf * 40503u ^ (attempt * 0x9E3779B9u);
    int n = snprintf(buf, cap, "%s.tmp-%08x-%ld-%llu-%06x", path, (unsigned)host_tag(), pid, start,
                     r & 0xFFFFFFu);
    return n > 0 && (size_t)n < cap ? 0 : -1;
}

/* Reads a run of digits (base 10 or 16) of at most @p max characters at
 * *@p s, exactly @p exact of them when not 0, and moves past it. */
static int
take_number(const char **s, int base, int exact, int max, unsigned long long *out) {
    const char *p = *s;
    int n = 0;
    while (base == 16 ? isxdigit((unsigned char)p[n]) : isdigit((unsigned char)p[n]))
        n++;
    if (n == 0 || n > max || (exact && n != exact))
        return 0;
    char num[32];
    memcpy(num, p, (size_t)n);
    num[n] = '\0';
    *out = strtoull(num, NULL, base);
    *s = p + n;
    return 1;
}

int
vv_tmp_parse(const char *name, const char *base, uint32_t *host, long *pid,
             unsigned long long *start) {
    const size_t bn = strlen(base);
    if (strncmp(name, base, bn) != 0 || strncmp(name + bn, ".tmp-", 5) != 0)
        return 0;
    const char *p = name + bn + 5;
    unsigned long long h, id, st, r;
    if (!take_number(&p, 16, 8, 8, &h) || *p++ != '-' || !take_number(&p, 10, 0, 10, &id) ||
        *p++ != '-' || !take_number(&p, 10, 0, 20, &st) || *p++ != '-' ||
        !take_number(&p, 16, 6, 6, &r) || *p != '\0' || id == 0 || id > 0x7FFFFFFF)
        return 0;
    *host = (uint32_t)h;
    *pid = (long)id;
    *start = st;
    return 1;
}

/* Removes folder @p name of @p dfd and everything under it, on device
 * @p dev only, never through a symbolic link (links are removed, not
 * followed). Returns 0 when it is gone. */
static int
remove_tree_at(int dfd, const char *name, dev_t dev, int depth) {
    if (depth > TMP_TREE_DEPTH)
        return -1;
    int fd = openat(dfd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0)
        return errno == ENOENT ? 0 : -1; /* gone: another sweeper was first */
    struct stat st;
    if (fstat(fd, &st) != 0 || st.st_dev != dev) { /* a mount point: not ours */
        close(fd);
        return -1;
    }
    DIR *d = fdopendir(fd);
    if (!d) {
        close(fd);
        return -1;
    }
    for (int pass = 0; pass < TMP_TREE_PASSES; pass++) {
        int removed = 0;
        struct dirent *e;
        rewinddir(d);
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            struct stat es;
            if (fstatat(fd, e->d_name, &es, AT_SYMLINK_NOFOLLOW) != 0)
                continue;
            if (S_ISDIR(es.st_mode) ? remove_tree_at(fd, e->d_name, dev, depth + 1) == 0
                                    : unlinkat(fd, e->d_name, 0) == 0)
                removed++;
        }
        if (!removed)
            break;
    }
    closedir(d);
    return unlinkat(dfd, name, AT_REMOVEDIR) == 0 || errno == ENOENT ? 0 : -1;
}

int
vv_tmp_sweep(const char *path) {
    if (!path || !*path)
        return 0;
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    if (!*base)
        return 0;
    char *dir = slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path)) : NULL;
    if (slash && !dir)
        return 0;
    int dfd = open(dir ? dir : ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(dir);
    if (dfd < 0)
        return 0;
    struct stat ds;
    int rfd = fstat(dfd, &ds) == 0 ? dup(dfd) : -1;
    DIR *d = rfd >= 0 ? fdopendir(rfd) : NULL;
    if (!d) {
        if (rfd >= 0)
            close(rfd);
        close(dfd);
        return 0;
    }
    const uint32_t mine = host_tag();
    const uid_t me = geteuid();
    int removed = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        uint32_t host;
        long pid;
        unsigned long long start;
        if (!vv_tmp_parse(e->d_name, base, &host, &pid, &start) || host != mine ||
            writer_alive(pid, start))
            continue;
        /* only what such a writer makes, of this user, on this file system */
        struct stat st;
        if (fstatat(dfd, e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 || st.st_uid != me ||
            st.st_dev != ds.st_dev)
            continue;
        if (S_ISREG(st.st_mode)   ? unlinkat(dfd, e->d_name, 0) == 0
            : S_ISDIR(st.st_mode) ? remove_tree_at(dfd, e->d_name, ds.st_dev, 0) == 0
                                  : 0)
            removed++;
    }
    closedir(d);
    close(dfd);
    return removed;
}
