/*
 * Error reporting, volume loading and the terminal progress bar of the CLI.
 */
#include <errno.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "volvis/sys/format.h"

/* The last error line (without "volvis: "), and whether error lines are
 * kept only (the ranks other than 0 under mpirun print nothing). */
static char last_error[4096];
static int errors_quiet;

const char *
cli_last_error(void) {
    return last_error;
}

void
cli_errors_quiet(int quiet) {
    errors_quiet = quiet;
}

/* Writes "volvis: " + message + "\n" as one line: embedded newlines become
 * "; ", other control bytes (an argument's escape sequence) \xNN. */
static void
print_line(const char *msg) {
    static const char hex[] = "0123456789abcdef";
    char buf[4096];
    size_t n = 0;
    for (const char *p = msg; *p && n + 5 < sizeof buf; p++) {
        const unsigned char c = (unsigned char)*p;
        if (c == '\n' || c == '\r') {
            if (p[1] == '\0')
                break;
            buf[n++] = ';';
            buf[n++] = ' ';
        } else if (c < 0x20 || c == 0x7f) {
            buf[n++] = '\\';
            buf[n++] = 'x';
            buf[n++] = hex[c >> 4];
            buf[n++] = hex[c & 15];
        } else {
            buf[n++] = *p;
        }
    }
    buf[n] = '\0';
    snprintf(last_error, sizeof last_error, "%s", buf);
    if (errors_quiet)
        return;
    fprintf(stderr, "volvis: %s\n", buf);
    fflush(stderr);
}

void
cli_error(const char *fmt, ...) {
    char msg[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    print_line(msg);
}

int
cli_usage_error(const cli_args *a, const char *fmt, ...) {
    char msg[3072];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (a && a->cmd)
        cli_error("%s: %s (see 'volvis %s --help')", a->cmd, msg, a->cmd);
    else
        cli_error("%s (see 'volvis --help')", msg);
    return CLI_EXIT_USAGE;
}

static const char *
base_name(const char *path) {
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

int
cli_fail(vv_status s, const char *path) {
    const char *msg = vv_error_message();
    char fallback[128];
    if (!msg || !*msg) {
        snprintf(fallback, sizeof fallback, "failed (%s)", vv_status_name(s));
        msg = fallback;
    }
    if (path && !strstr(msg, path) && !strstr(msg, base_name(path)))
        cli_error("%s: %s", path, msg);
    else
        cli_error("%s", msg);
    return s == VV_ERR_CANCELLED ? CLI_EXIT_CANCEL : CLI_EXIT_FAIL;
}

int
cli_check_readable(const char *path) {
    struct stat st;
    if (stat(path, &st) != 0) {
        cli_error("%s: %s", path, strerror(errno));
        return CLI_EXIT_FAIL;
    }
    if (S_ISDIR(st.st_mode)) {
        cli_error("%s: is a directory", path);
        return CLI_EXIT_FAIL;
    }
    if (access(path, R_OK) != 0) {
        cli_error("%s: %s", path, strerror(errno));
        return CLI_EXIT_FAIL;
    }
    return 0;
}

int
cli_check_readable_input(const char *path) {
    /* a remote store (http://, https://, s3://): the library fetches it */
    if (vv_path_is_url(path))
        return 0;
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        if (access(path, R_OK | X_OK) != 0) {
            cli_error("%s: %s", path, strerror(errno));
            return CLI_EXIT_FAIL;
        }
        return 0;
    }
    return cli_check_readable(path);
}

int
cli_parse_series_channel(const cli_args *a, int *series, int *channel, int *time) {
    int rc;
    const char *s;
    *series = 0;
    *channel = -1;
    *time = -1;
    if ((s = cli_get(a, "series")) && (rc = cli_parse_int(a, "series", s, 1, 1000000, series)))
        return rc;
    if ((s = cli_get(a, "channel")) && (rc = cli_parse_int(a, "channel", s, 0, 1000000, channel)))
        return rc;
    if ((s = cli_get(a, "time")) && (rc = cli_parse_int(a, "time", s, 0, 1000000, time)))
        return rc;
    return 0;
}

int
cli_load_volume(const char *path, const vv_raw_params *raw, vv_volume **out) {
    return cli_load_volume_sc(path, raw, 0, -1, -1, NULL, out);
}

int
cli_load_volume_sc(const char *path, const vv_raw_params *raw, int series, int channel, int time,
                   vv_load_info *info, vv_volume **out) {
    return cli_load_volume_level(path, raw, series, channel, time, 0, info, out);
}

int
cli_load_volume_level(const char *path, const vv_raw_params *raw, int series, int channel, int time,
                      int level, vv_load_info *info, vv_volume **out) {
    *out = NULL;
    int rc = raw ? cli_check_readable(path) : cli_check_readable_input(path);
    if (rc)
        return rc;
    vv_load_options opt;
    vv_load_options_init(&opt);
    opt.series = series;
    opt.channel = channel;
    opt.time = time;
    opt.level = level;
    opt.info = info;
    if (raw) {
        opt.format = VV_FORMAT_RAW;
        opt.has_raw = 1;
        opt.raw = *raw;
    }
    vv_error_clear();
    vv_status s = vv_volume_load(out, path, &opt);
    if (s != VV_OK) {
        vv_volume_free(*out);
        *out = NULL;
        return cli_fail(s, path);
    }
    return 0;
}

/* ---- progress bar and Ctrl-C --------------------------------------------- */

/* Set from the SIGINT handler; the only global state of the tool. */
static volatile sig_atomic_t g_interrupted;
static struct sigaction g_old_sigint;

static void
on_sigint(int sig) {
    (void)sig;
    g_interrupted = 1;
}

int
cli_interrupted(void) {
    return g_interrupted != 0;
}

#define BAR_WIDTH 30

static int
progress_cb(void *user, double fraction) {
    cli_progress *pr = user;
    if (pr->draw) {
        if (!(fraction >= 0))
            fraction = 0;
        if (fraction > 1)
            fraction = 1;
        int pct = (int)(fraction * 100.0 + 1e-9);
        /* time left from the rate so far, once a second has passed */
        const double elapsed = cli_now() - pr->start;
        int left = -1;
        if (elapsed >= 1.0 && fraction > 0.01 && fraction < 1)
            left = (int)(elapsed * (1 - fraction) / fraction + 0.5);
        if (pct != pr->last_pct || left != pr->last_left) {
            char bar[BAR_WIDTH + 1];
            int fill = (int)(fraction * BAR_WIDTH + 1e-9);
            for (int i = 0; i < BAR_WIDTH; i++)
                bar[i] = i < fill ? '#' : ' ';
            bar[BAR_WIDTH] = '\0';
            if (left >= 0)
                fprintf(stderr, "\r[%s] %3d%%  ~%d s left   ", bar, pct, left);
            else
                fprintf(stderr, "\r[%s] %3d%%", bar, pct);
            fflush(stderr);
            pr->last_pct = pct;
            pr->last_left = left;
            pr->drawn = 1;
        }
    }
    return g_interrupted ? 1 : 0;
}

void
cli_progress_begin(cli_progress *pr, int quiet) {
    pr->draw = !quiet && isatty(STDERR_FILENO);
    pr->last_pct = -1;
    pr->last_left = -1;
    pr->start = cli_now();
    pr->drawn = 0;
    pr->p.fn = progress_cb;
    pr->p.user = pr;
    g_interrupted = 0;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &g_old_sigint);
}

void
cli_progress_end(cli_progress *pr) {
    if (pr->drawn) {
        fprintf(stderr, "\r%*s\r", BAR_WIDTH + 28, "");
        fflush(stderr);
    }
    pr->drawn = 0;
    sigaction(SIGINT, &g_old_sigint, NULL);
}

double
cli_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* " (.a, .b)" of a NULL-terminated extension list, or "". */
static void
extension_list(char *buf, size_t cap, const char *const *ext) {
    buf[0] = '\0';
    for (int i = 0; ext && ext[i]; i++) {
        size_t k = strlen(buf);
        snprintf(buf + k, cap - k, "%s.%s", i ? ", " : " (", ext[i]);
    }
    if (buf[0]) {
        size_t k = strlen(buf);
        snprintf(buf + k, cap - k, ")");
    }
}

void
cli_print_formats(FILE *out, int grids) {
    int n = 0;
    char ext[256];
    const vv_format_record *const *t = vv_format_table(&n);
    fprintf(out, "Volume formats (detected from the content; --format NAME where a command "
                 "takes it):\n");
    for (int i = 0; i < n; i++) {
        if (t[i]->holds != VV_DATA_VOLUME)
            continue;
        extension_list(ext, sizeof ext, t[i]->extensions);
        fprintf(out, "  %s%s: %s%s\n      %s\n", t[i]->name, ext,
                !t[i]->read && !t[i]->open_store ? "write"
                : t[i]->write                    ? "read and write"
                                                 : "read",
                t[i]->flags & VV_FORMAT_FLAG_FOLDER ? ", files or folders" : "", t[i]->doc);
    }
    if (!grids)
        return;
    fprintf(out, "Irregular grid formats (detected from the content or the name):\n");
    for (int i = 0; i < n; i++) {
        if (t[i]->holds != VV_DATA_GRID)
            continue;
        extension_list(ext, sizeof ext, t[i]->extensions);
        fprintf(out, "  %s%s: %s\n      %s\n", t[i]->name, ext,
                t[i]->write_grid ? "read and write" : "read", t[i]->doc);
    }
}

void
cli_writable_formats(char *buf, size_t cap, const char *sep, int extensions) {
    int n = 0, k = 0;
    const vv_format_record *const *t = vv_format_table(&n);
    buf[0] = '\0';
    for (int i = 0; i < n; i++) {
        if (!t[i]->write || t[i]->holds != VV_DATA_VOLUME)
            continue;
        for (const char *const *e = extensions ? vv_format_record_write_extensions(t[i])
                                               : &t[i]->name;
             e && *e; e++) {
            size_t len = strlen(buf);
            snprintf(buf + len, cap - len, "%s%s%s", k++ ? sep : "", extensions ? "." : "", *e);
            if (!extensions)
                break;
        }
    }
}

int
cli_ends_with(const char *s, const char *suffix) {
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

void
cli_numbered_path(const char *out, char tag, int n, char *buf, size_t cap) {
    size_t len = strlen(out);
    size_t stem = cli_ends_with(out, ".png") || cli_ends_with(out, ".PNG") ? len - 4 : len;
    snprintf(buf, cap, "%.*s_%c%04d%s", (int)stem, out, tag, n, out + stem);
}
