/*
 * `volvis serve`: the browser view (docs/serve.md; the wire protocol in
 * docs/serve-protocol.md). Internal to apps/volvis/serve/; symbols take the
 * prefix `srv_`.
 *
 * Threads: one libwebsockets service thread runs every connection, parses
 * the clients' messages and edits the sessions' Worlds (under each
 * session's lock); one render thread per session draws snapshots of its
 * World (vv_world_clone) and hands finished frames back through the
 * session's frame slot, waking the service thread with
 * lws_cancel_service. Nothing else is shared.
 */
#ifndef VOLVIS_SERVE_H
#define VOLVIS_SERVE_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "../cli.h"

/* ---- messages (serve_msg.c: pure, no libwebsockets; fuzzed by fuzz_serve_msg) ---- */

/** Largest text message a client may send, bytes. */
#define SRV_MSG_MAX 65536
/** Largest path a message may name, bytes. */
#define SRV_PATH_MAX 1024
/** Largest URL a message or the command line may name, bytes. */
#define SRV_URL_MAX 2048
/** Sides of the 3-D view and of slice images, pixels. */
#define SRV_VIEW_MIN 16
#define SRV_VIEW_MAX 4096
#define SRV_SLICE_MAX 2048

typedef enum srv_msg_type {
    SRV_HELLO,
    SRV_RESIZE,
    SRV_NAV,
    SRV_RESET_VIEW,
    SRV_MODE,
    SRV_PRESET,
    SRV_CHANNEL,
    SRV_TIME,
    SRV_SLICE,
    SRV_PROBE,
    SRV_PNG,
    SRV_THUMBNAILS,
    SRV_LIST,
    SRV_OPEN,
    SRV_SAVE
} srv_msg_type;

/** One client message, parsed and range-checked (docs/serve-protocol.md). */
typedef struct srv_msg {
    srv_msg_type type;
    int width, height;        /**< HELLO, RESIZE, SLICE, PROBE */
    int motion;               /**< NAV: VV_NAV_ROTATE, VV_NAV_PAN or VV_NAV_ZOOM */
    double dx, dy, factor;    /**< NAV */
    long long seq;            /**< NAV: the client's input counter (0 when absent) */
    int moving;               /**< NAV: 1 while the motion goes on */
    vv_render_mode mode;      /**< MODE */
    int has_isovalue;         /**< MODE */
    double isovalue;          /**< MODE */
    char name[64];            /**< PRESET */
    int index;                /**< CHANNEL, SLICE, PROBE (slice number), TIME (step) */
    int has_visible, visible; /**< CHANNEL */
    int has_color;            /**< CHANNEL */
    vv_vec3 color;            /**< CHANNEL, RGB 0..1 */
    vv_slice_axis axis;       /**< SLICE, PROBE (not oblique) */
    int has_window;           /**< SLICE: window and level given */
    double window, level;     /**< SLICE */
    double x, y;              /**< PROBE: pixel of the slice image */
    int size;                 /**< THUMBNAILS */
    char path[SRV_PATH_MAX];  /**< LIST, OPEN, SAVE: relative to the root */
    char url[SRV_URL_MAX];    /**< OPEN: a URL instead of a path ("" none; not yet checked
                                   against the allowed ones: srv_url_allowed) */
} srv_msg;

/**
 * Parses one text message of @p len bytes (not NUL-terminated). Returns 0,
 * or -1 with a one-line reason in @p why (the message is refused: the
 * client is closed). Checks every field's type and range; never allocates
 * more than Jansson does for @p len bytes. Reentrant.
 */
int srv_msg_parse(const char *text, size_t len, srv_msg *out, char *why, size_t cap);

/**
 * A path of a message resolved inside the root folder @p root (a real path,
 * no trailing slash): relative, no "..", no empty or "." components, no
 * control bytes; its real path (symbolic links followed) must lie inside
 * @p root. @p kind: 0 an existing file or folder, 1 a folder, 2 a new or
 * existing file to write (its folder must exist inside the root, its name
 * end in .json, and it must not be a link or a folder). The full path goes
 * to @p out. Returns 0, or -1 with the reason in @p why.
 */
int srv_path_resolve(const char *root, const char *rel, int kind, char *out, size_t cap, char *why,
                     size_t why_cap);

/**
 * Opens @p rel (relative, no "." or ".." components: srv_path_resolve's
 * checks) beneath the folder @p dirfd with open(2) @p flags (O_CLOEXEC
 * added): openat2(2) with RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS, so no
 * link, absolute or relative, swapped in at any moment, leads the open out
 * of @p dirfd (EXDEV, ELOOP); where the kernel has no openat2 (ENOSYS), a
 * walk of openat(2) with O_NOFOLLOW, component by component, that follows
 * no link at all (ELOOP). "" is @p dirfd itself. Returns the new fd, or -1
 * with errno. Reentrant.
 */
int srv_open_beneath(int dirfd, const char *rel, int flags);

/** Tests only: 1 makes srv_open_beneath take the walk, as on a kernel without openat2. */
extern int srv_openat2_off;

/**
 * Checks scene file @p scene (a real path inside @p root, as
 * srv_path_resolve gives it) for entries that leave the root: at any depth of
 * its JSON, every member "file", "image" (a texture) or "volume" (a solid
 * texture) with a string value, resolved as
 * the scene loader does (relative to the scene's folder; an absolute path
 * as it is), must name a path inside @p root, and opening it beneath the
 * root (srv_open_beneath) must not be refused for a link out; an entry
 * that is a URL must be allowed (srv_url_allowed with @p urls and
 * @p prefixes, as the browser's own opens). A scene that
 * is not JSON, or an entry that does not exist, is left to the door (its
 * own error). Returns 0, or -1 with one line naming the scene (relative to
 * the root) and the entry in @p why.
 */
int srv_scene_confined(const char *root, const char *scene, char *const *urls, int n_urls,
                       char *const *prefixes, int n_prefixes, char *why, size_t cap);

/**
 * The normal form of URL @p in into @p out: scheme http, https or s3
 * (lower case), host in lower case (an IPv6 literal in brackets; for s3 the
 * bucket), port (none for s3; the scheme's default dropped), then the path
 * ("/" when empty) with every percent-escape of an unreserved character
 * decoded and the others in upper case, then the query as given; a
 * fragment is dropped. Refused: user information, a percent-encoded "/",
 * "\" or NUL, a "." or ".." or empty path segment (after decoding), a
 * backslash, spaces, control and non-ASCII bytes, a malformed escape or
 * port. Returns 0, or -1 with the reason in @p why. Reentrant.
 */
int srv_url_normalize(const char *in, char *out, size_t cap, char *why, size_t why_cap);

/**
 * 1 when normalised URL @p url (srv_url_normalize) is one of the @p n_urls
 * given (normalised) or lies under one of the @p n_prefixes prefixes
 * (normalised, no query): the same scheme, host and port, and a path that
 * starts with the prefix's on a segment boundary (prefix "/data" or
 * "/data/" takes "/data/x", never "/database"), without a query. 0
 * otherwise. Reentrant.
 */
int srv_url_allowed(const char *url, char *const *urls, int n_urls, char *const *prefixes,
                    int n_prefixes);

/** 1 when @p s names a URL (a scheme of letters, digits, "+", "-" or "." then "://"). */
int srv_is_url(const char *s);

/**
 * 1 when folder @p path holds one dataset rather than files to choose from:
 * a Zarr store (a name ending in .zarr, or a .zgroup, .zarray or .zattrs in
 * it). The file browser opens it rather than entering it.
 */
int srv_folder_is_store(const char *path);

/* ---- buffers sent to clients ---------------------------------------------------------- */

/** A message ready for lws_write: @p pre bytes of headroom, then @p len bytes. */
typedef struct srv_buf {
    int refs; /* atomic */
    int binary;
    size_t len;
    unsigned char *data; /**< data + SRV_PRE is the message */
} srv_buf;

/** Headroom libwebsockets needs in front of a message (LWS_PRE, checked in serve_main.c). */
#define SRV_PRE 16

/** A text message (a copy of @p text). NULL when out of memory. */
srv_buf *srv_buf_text(const char *text, size_t len);
/**
 * A binary message: kind (4 ASCII bytes), uint32 LE header length, the JSON
 * header, then @p payload. NULL when out of memory.
 */
srv_buf *srv_buf_binary(const char kind[4], const char *header, const void *payload, size_t n);
srv_buf *srv_buf_ref(srv_buf *b);
void srv_buf_unref(srv_buf *b);

/* ---- sessions (serve_session.c) ----------------------------------------------------- */

typedef struct srv_server srv_server;
typedef struct srv_session srv_session;
typedef struct srv_client srv_client;

/** Largest number of queued replies for one client; beyond it the client is too slow. */
#define SRV_QUEUE_MAX 64

struct srv_client {
    uint64_t id;
    void *wsi; /**< its struct lws */
    srv_session *session;
    srv_buf *queue[SRV_QUEUE_MAX]; /**< replies, oldest first (under the session's lock) */
    int n_queue;
    uint64_t sent_frame; /**< seq of the last frame sent */
    char *rx;            /**< message being received */
    size_t rx_len;
    int close_code; /**< != 0: close with this code and reason at the next write */
    char close_reason[120];
    int overflowed; /**< the queue overflowed */
    /** The newest state message (`remote`) not yet sent (NULL: none), under the session's
     *  lock: a newer one replaces it, none is dropped, and it goes out once the queue is
     *  empty (srv_session_send_latest) */
    srv_buf *latest;
    srv_client *next;
};

/** The server's settings and state. */
struct srv_server {
    char root[4096];    /**< real path of --root */
    char web_dir[4096]; /**< the client's files */
    char initial[4096]; /**< the file or URL opened in every new session ("" none) */
    char **urls;        /**< the URLs given on the command line, normalised */
    int n_urls;
    char **prefixes; /**< --allow-url prefixes, normalised */
    int n_prefixes;
    uint64_t memory_limit;
    int shared;
    int threads;
    void *context;        /**< struct lws_context */
    pthread_mutex_t lock; /**< the clients list and sessions */
    srv_client *clients;
    srv_session *shared_session;
    uint64_t next_client_id;
    volatile int stopping;
    int verbose;
    int ranks; /**< MPI ranks rendering every frame (1: this process alone) */
    uint64_t next_session_id;
};

/** A new session of @p srv showing srv->initial (opened by its render thread). */
srv_session *srv_session_new(srv_server *srv);
/**
 * Stops the session's render thread and frees it (no client may still point
 * at it). Service thread only: under MPI it runs the frames the thread may
 * be waiting for until the thread has ended.
 */
void srv_session_free(srv_session *s);
/** Attaches a client (under srv->lock). */
void srv_session_attach(srv_session *s, srv_client *c);
/** Detaches a client; returns the clients left. */
int srv_session_detach(srv_session *s, srv_client *c);
/**
 * Handles one parsed message of client @p c (service thread). Returns 0, or
 * -1 when the client must be closed (c->close_code and reason set).
 */
int srv_session_handle(srv_session *s, srv_client *c, const srv_msg *m);
/**
 * The next message for @p c, or NULL: a queued reply first, then its latest
 * state message (srv_session_send_latest), then the session's newest frame
 * when it is newer than the last sent. The caller
 * owns one reference. Service thread.
 */
srv_buf *srv_session_next_out(srv_session *s, srv_client *c);
/** The close code set for @p c (0 none) and its reason, read under the session's lock. */
int srv_session_close_code(srv_session *s, srv_client *c, char *reason, size_t cap);
/** 1 when @p c has something to send. */
int srv_session_has_out(srv_session *s, srv_client *c);
/**
 * Makes state message @p text (copied; a `remote` message: counts that the
 * newest supersedes) the one @p c hears next of its kind: it replaces one
 * not yet sent, so a client that reads slowly misses intermediate states,
 * never the last one, and never its replies (the slot takes no place in the
 * queue and goes out when the queue is empty, before a frame). Service
 * thread.
 */
void srv_session_send_latest(srv_session *s, srv_client *c, const char *text);

/**
 * The World of file @p path through the door (vv_world_open: a scene, a
 * volume file's every channel as one object, a grid), out of core under
 * srv->memory_limit where the file can be read so; what the door found in
 * *@p info (may be NULL), the slice views' window and level among it. 0,
 * or -1 with the one-line error in @p why. Thread-safe.
 */
int srv_open_world(const srv_server *srv, const char *path, vv_world **out,
                   vv_world_open_info *info, char *why, size_t cap);

/** The World's first volume object with voxels (its data: slices, presets, state), or NULL. */
vv_object *srv_first_volume(const vv_world *w);

/* ---- MPI (serve_mpi.c): rank 0 serves, every rank renders every frame ---------------- */

typedef struct srv_mpi_job srv_mpi_job;
/** Collective start on every rank (vv_parallel_new): VV_OK on all, or the same error. */
vv_status srv_mpi_start(void);
/**
 * Rank 0, any render thread: draws @p w (a snapshot; @p path the file it was
 * opened from, the same on every rank) through @p view with every rank into
 * @p out (view's size), waiting for the service thread to run it.
 */
vv_status srv_mpi_render(srv_server *srv, uint64_t session, const char *path, const vv_world *w,
                         const vv_view *view, int quality, vv_image *out);
/** Rank 0, service thread: runs the frames posted; returns how many. */
int srv_mpi_service(srv_server *srv);
/** Rank 0, service thread: tells the other ranks to stop. */
void srv_mpi_stop(void);
/** Ranks > 0: draw the frames rank 0 announces until it stops; the exit status. */
int srv_mpi_worker(srv_server *srv);

/** Wakes the service thread (lws_cancel_service on srv->context). */
void srv_wake(srv_server *srv);

/** JPEG of @p pixels (RGBX, 4 bytes a pixel, or grey, 1 byte; rows top to bottom) at @p quality
 * into a new buffer (tjFree); 0 or -1. @p handle: a tjhandle for compression. */
int srv_jpeg(void *handle, const uint8_t *rgb, int width, int height, int quality, int grey,
             unsigned char **out, unsigned long *size);

/** JPEG of @p yuv (vv_pixels8's VV_PIXELS8_YUV420 planes of a @p width x @p height frame)
 * at @p quality, 4:2:0, into a new buffer (tjFree): the JPEG srv_jpeg makes of the frame's
 * RGBX, without libjpeg-turbo's colour pass. 0 or -1. @p handle: a tjhandle for compression. */
int srv_jpeg_yuv420(void *handle, const uint8_t *yuv, int width, int height, int quality,
                    unsigned char **out, unsigned long *size);

#endif
