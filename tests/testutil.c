#include "testutil.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

const char *
vt_data(const char *rel) {
    static _Thread_local char buf[8][1024];
    static _Thread_local int slot;
    slot = (slot + 1) % 8;
    snprintf(buf[slot], sizeof buf[slot], "%s/%s", VV_DATA_DIR, rel);
    return buf[slot];
}

static void
mkdir_p(const char *path) {
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; p++) {
        if (*p == '/') {
            *p = 0;
            mkdir(tmp, 0755);
            *p = '/';
        }
    }
    mkdir(tmp, 0755);
}

const char *
vt_outdir(const char *name) {
    static char buf[1024];
    snprintf(buf, sizeof buf, "%s/test-out/%s", VV_BINARY_DIR, name);
    mkdir_p(buf);
    return buf;
}

void
vt_write_file(const char *path, const void *data, size_t n) {
    FILE *f = fopen(path, "wb");
    if (!f)
        fail_msg("cannot write %s: %s", path, strerror(errno));
    if (n && fwrite(data, 1, n, f) != n)
        fail_msg("short write %s", path);
    fclose(f);
}

unsigned char *
vt_read_file(const char *path, size_t *n) {
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot read %s: %s", path, strerror(errno));
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)len + 1);
    assert_non_null(buf);
    if (len && fread(buf, 1, (size_t)len, f) != (size_t)len)
        fail_msg("short read %s", path);
    buf[len] = 0;
    fclose(f);
    *n = (size_t)len;
    return buf;
}
