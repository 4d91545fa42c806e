/*
 * Input latency: from a raw event to the action reaching the application,
 * through the replay driver (a recorded mouse drag on a virtual clock) and
 * through the network driver (a client writes a line on a Unix socket, the
 * manager wakes on its descriptor). Also shows that a manager waiting with
 * devices open uses no CPU (process CPU time over 1 s of poll()).
 *
 * Prints: anchor=volvis op=input_latency dataset=replay|network value=... unit=ms
 *         anchor=volvis op=input_idle_cpu dataset=network value=... unit=ms
 */
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "util.h"
#include "volvis/input.h"

#define N_EVENTS 20000

typedef struct probe {
    double got; /* wall time when the last action arrived */
    int n;
} probe;

static void
on_action(void *user, const vv_input_action *a) {
    probe *p = user;
    (void)a;
    p->got = bench_now();
    p->n++;
}

static void
bench_replay(const char *dir) {
    char path[512];
    snprintf(path, sizeof path, "%s/bench-input-drag.vvin", dir);
    FILE *fp = fopen(path, "w");
    if (!fp)
        bench_die("bench_input", path);
    fprintf(fp, "volvis-input 1\ndevice 1 mouse bench mouse\n0 button 1 1 1\n");
    for (int i = 0; i < N_EVENTS; i++)
        fprintf(fp, "%.6f pointer 1 0 %d %d\n", 0.001 * (i + 1), 100 + i % 500, 200 + i % 300);
    fclose(fp);
    vv_input_manager *m;
    if (vv_input_manager_new(&m, NULL) != VV_OK)
        bench_die("bench_input", "manager");
    probe p = {0, 0};
    vv_input_manager_subscribe(m, NULL, on_action, &p, NULL);
    if (vv_input_manager_open_replay(m, path, 0, 1, NULL, NULL) != VV_OK)
        bench_die("bench_input", "replay");
    vv_input_manager_dispatch(m, 0); /* the press */
    double *lat = malloc(N_EVENTS * sizeof *lat);
    int n = 0;
    for (int i = 0; i < N_EVENTS; i++) {
        /* each event becomes due at virtual time 0.001 (i + 1): time one dispatch */
        double t0 = bench_now();
        int before = p.n;
        vv_input_manager_dispatch(m, 0.001 * (i + 1));
        if (p.n > before)
            lat[n++] = (p.got - t0) * 1e3;
    }
    bench_emit("input_latency", "replay", bench_median(lat, n), "ms");
    free(lat);
    vv_input_manager_free(m);
    remove(path);
}

static void
bench_network(const char *dir) {
    char path[108];
    snprintf(path, sizeof path, "%.80s/bench-input.sock", dir);
    vv_input_manager *m;
    if (vv_input_manager_new(&m, NULL) != VV_OK || vv_input_manager_listen(m, path) != VV_OK)
        bench_die("bench_input", "listen");
    probe p = {0, 0};
    vv_input_manager_subscribe(m, NULL, on_action, &p, NULL);
    int fd = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un a;
    memset(&a, 0, sizeof a);
    a.sun_family = AF_UNIX;
    memcpy(a.sun_path, path, strlen(path) + 1);
    if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a) != 0)
        bench_die("bench_input", "connect");
    struct pollfd pf = {vv_input_manager_fd(m), POLLIN, 0};
    poll(&pf, 1, 1000);
    vv_input_manager_dispatch(m, bench_now());
    const char *decl = "device 1 network bench\n";
    if (write(fd, decl, strlen(decl)) < 0)
        bench_die("bench_input", "write");
    poll(&pf, 1, 1000);
    vv_input_manager_dispatch(m, bench_now());
    enum { N = 2000 };
    double lat[N];
    int n = 0;
    for (int i = 0; i < N; i++) {
        char line[64];
        int len = snprintf(line, sizeof line, "axis 1 0 %.3f\n", (i % 100) / 100.0);
        int before = p.n;
        double t0 = bench_now();
        if (write(fd, line, (size_t)len) != len)
            bench_die("bench_input", "write");
        while (p.n == before) {
            if (poll(&pf, 1, 1000) <= 0)
                break;
            vv_input_manager_dispatch(m, bench_now());
        }
        if (p.n > before)
            lat[n++] = (p.got - t0) * 1e3;
    }
    bench_emit("input_latency", "network", bench_median(lat, n), "ms");

    /* idle: one second in poll() on the manager's descriptor with a client connected */
    double c0 = bench_cpu_now(), w0 = bench_now();
    while (bench_now() - w0 < 1.0) {
        double to = vv_input_manager_timeout(m, bench_now());
        int ms = to < 0 ? 1000 : (int)(to * 1000);
        poll(&pf, 1, ms > 1000 ? 1000 : ms);
        vv_input_manager_dispatch(m, bench_now());
    }
    bench_emit("input_idle_cpu", "network", (bench_cpu_now() - c0) * 1e3, "ms");
    close(fd);
    vv_input_manager_free(m);
}

int
main(int argc, char **argv) {
    const char *dir = argc > 1 ? argv[1] : "/tmp";
    bench_replay(dir);
    bench_network(dir);
    return 0;
}
