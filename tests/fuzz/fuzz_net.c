/*
 * libFuzzer harness: the network device protocol (src/input/net.c), what a
 * remote device sends over the listener's socket (docs/input.md). Each
 * input is one connection: a manager listens on a Unix socket in the
 * harness's folder, a client connects, sends the input (in pieces cut at
 * each "\n--PIECE--\n", so lines split across reads are fuzzed too), and
 * the manager reads, parses, answers and drops what is malformed; then the
 * client hangs up and the manager is freed. Its warnings must be one
 * printable line.
 */
#include <math.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static vv_input_devinfo_db *db;

/* Lets the manager read everything sent so far (no waiting: the socket is
 * local, and poll says when it has read all). */
static void
pump(vv_input_manager *m) {
    struct pollfd p = {vv_input_manager_fd(m), POLLIN, 0};
    for (int i = 0; i < 256 && poll(&p, 1, 0) == 1; i++)
        vv_input_manager_dispatch(m, 1.0);
}

/* Reads and drops what the server answered. */
static void
drain(int fd) {
    char buf[4096];
    struct pollfd p = {fd, POLLIN, 0};
    while (poll(&p, 1, 0) == 1 && read(fd, buf, sizeof buf) > 0)
        ;
}

/* The first @p k bytes of @p cut in @p d of @p n, or NULL. */
static const uint8_t *
find(const uint8_t *d, size_t n, const char *cut, size_t k) {
    for (size_t i = 0; i + k <= n; i++)
        if (!memcmp(d + i, cut, k))
            return d + i;
    return NULL;
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *none[1] = {NULL};
    if (!db && vv_input_devinfo_db_load(&db, none, 1) != VV_OK)
        __builtin_trap();
    vv_input_manager *m = NULL;
    if (vv_input_manager_new(&m, db) != VV_OK)
        return 0;
    char path[512];
    snprintf(path, sizeof path, "%s/net.sock", fuzz_dir());
    unlink(path);
    if (vv_input_manager_listen(m, path) != VV_OK)
        __builtin_trap(); /* the machine, not the input */
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    snprintf(a.sun_path, sizeof a.sun_path, "%s", path);
    if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a) != 0)
        __builtin_trap();
    pump(m);
    static const char cut[] = "\n--PIECE--\n";
    size_t off = 0;
    while (off < size) {
        const uint8_t *end = find(data + off, size - off, cut, sizeof cut - 1);
        const size_t n = end ? (size_t)(end - (data + off)) : size - off;
        if (n && write(fd, data + off, n) != (ssize_t)n)
            break; /* the server hung up on this client */
        pump(m);
        drain(fd);
        off += n + (end ? sizeof cut - 1 : 0);
    }
    close(fd);
    pump(m);
    for (const char *c = vv_input_manager_last_warning(m); *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f)
            __builtin_trap();
    vv_input_manager_free(m);
    unlink(path);
    return 0;
}
