/*
 * Byte sources under the chunked stores (not installed): where a store's
 * objects come from -- a local folder (pread), or HTTP(S) and S3
 * (libcurl; bytesrc_http.c). The readers (zarr_read.c, zarr3.c) ask for
 * (key, offset, length) through zr_store_get and zr_store_get_many and
 * never know which. Remote fetches run in this process (the library), not
 * in the reader sandbox: the bytes are checked and decoded by our own
 * parsers, as a local store's are (docs/security.md, "Remote data").
 */
#ifndef VOLVIS_IO_BYTESRC_H
#define VOLVIS_IO_BYTESRC_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/core.h"

/* off: the last len bytes; len: to the end of the object (zarr.h's ZR_SUFFIX, ZR_ALL) */
#define BS_SUFFIX UINT64_MAX
#define BS_ALL UINT64_MAX

/* One read of a batch: in, the object's key (relative to the store's
 * root), bytes [off, off + len) (off BS_SUFFIX: the last len bytes; len
 * BS_ALL: to the end; len 0: only whether it exists and its size), at
 * most max bytes, and optionally (stale NULL: never) whether nobody wants
 * it any more; out, a new buffer *out (free it) of n bytes, the object's
 * size (UINT64_MAX when the server did not say), missing = 1 when the
 * object is absent (out NULL), cancelled = 1 when it was dropped unread
 * because stale answered 1 (out NULL, not an error: a view moved on).
 * stale(stale_u) is asked before the read starts and, by a remote source,
 * about every 50 ms while its request is in flight (the request is then
 * abandoned: its connection closed); it runs on the thread that called
 * get_many, with no lock of the source held, and must be thread-safe
 * against whoever makes the read stale. */
typedef struct bs_get {
    const char *key;
    uint64_t off, len, max;
    int (*stale)(void *stale_u);
    void *stale_u;
    unsigned char *out;
    size_t n;
    uint64_t size;
    int missing, cancelled;
} bs_get;

typedef struct vv_bytesrc vv_bytesrc;

/* A byte source's operations. get_many reads @p n ranges (all of them in
 * flight at once where the source can); VV_OK when every one is read or
 * missing, else the status and error of the first failing one in order
 * (the others' buffers freed). Thread-safe: many threads may call at once.
 * close frees the source. */
typedef struct vv_bytesrc_ops {
    const char *name; /* "local", "http", "s3" */
    vv_status (*get_many)(vv_bytesrc *src, bs_get *g, int n);
    void (*close)(vv_bytesrc *src);
} vv_bytesrc_ops;

struct vv_bytesrc {
    const vv_bytesrc_ops *ops;
};

/* A local folder's source: objects are files beneath @p root, refused
 * when they resolve (links) outside @p real ("" unchecked). On the stack:
 * no close needed. */
typedef struct bs_local {
    vv_bytesrc base;
    const char *root, *real;
} bs_local;
void bs_local_init(bs_local *s, const char *root, const char *real);

/* 1 when @p path names a remote store: http://, https://, s3:// or gs://
 * (a Google Cloud Storage bucket read anonymously at its public HTTPS
 * address), also behind Neuroglancer's precomputed://, n5://, zarr://,
 * zarr2:// or zarr3:// (bs_url_unprefix). */
int bs_is_url(const char *path);
/* @p url past Neuroglancer's data source prefixes (precomputed://,
 * n5://, zarr://, zarr2://, zarr3://): the URL itself. */
const char *bs_url_unprefix(const char *url);
/* The format row a Neuroglancer prefix of @p url names: "precomputed" or
 * "n5"; NULL for none or a Zarr prefix (the Zarr row tells v2 from v3). */
const char *bs_url_format(const char *url);

/* The name of store @p path in messages: a URL whole, a local path's base name. */
const char *bs_name(const char *path);

/* The remote source of the store at URL @p root (http, https, s3), made
 * on first use and kept for the process's life (its connections reused by
 * every later read); NULL with the error set (a malformed URL). */
vv_bytesrc *bs_remote(const char *root);

/* The number of requests the remote transport keeps in flight
 * (VOLVIS_HTTP_MAX_IN_FLIGHT, default 32): the threads a reader of a
 * remote store may wait on at once. */
int bs_http_in_flight(void);

/* ---- the remote transport's counts (vv_remote_stats, io.h; bytesrc.c) ---- */

/* One read's share of the process's counts: bytes it expects of the try
 * in flight (0 while not known) and, of them, those still counted
 * pending. Owned by the read (one thread at a time); the counts it updates
 * are atomic. */
typedef struct bs_count {
    uint64_t want, left;
    int open, sized;
} bs_count;

/* A read accepted: pending + 1, its @p want bytes pending (0: not known
 * until the server says). */
void bs_count_open(bs_count *c, uint64_t want);
/* A request for it sent: requests and in flight + 1, its bytes pending
 * again (a retry receives them anew). */
void bs_count_try(bs_count *c);
/* The server said the body's length @p n (taken when the read's was not
 * known). */
void bs_count_length(bs_count *c, uint64_t n);
/* @p n body bytes received. */
void bs_count_body(bs_count *c, uint64_t n);
/* A request ended (answered, failed or redirected): in flight - 1. */
void bs_count_landed(void);
/* The read answered (@p failed: for good): pending - 1, completed + 1, what
 * it still counted pending dropped. Again: nothing. */
void bs_count_close(bs_count *c, int failed);
/* The read dropped unanswered because nobody wants it (bs_get.stale):
 * pending - 1, cancelled + 1, what it still counted pending dropped.
 * Again, or after bs_count_close: nothing. */
void bs_count_cancel(bs_count *c);

/* The process's HTTP(S) and S3 requests so far: *requests started (each
 * try and redirect one), *max_in_flight the most in flight at once, over
 * every source and thread. VOLVIS_HTTP_STATS=1 prints them at exit, one
 * line on stderr ("volvis: http: N requests, at most M in flight").
 * Thread-safe. */
void bs_http_stats(uint64_t *requests, int *max_in_flight);

/* ---- S3 addressing (bytesrc_http.c; unit-tested) ---------------------- */

/* Where the objects of an S3 or HTTP root URL are and how they are asked
 * for. */
typedef struct bs_target {
    char base[4096];  /* the http(s) URL of the root (no trailing '/') */
    char shown[4096]; /* the root as given, without user information: in messages */
    int s3;           /* an S3 bucket (403 on a key may mean absent; signed) */
    int path_style;   /* S3: the bucket in the path (an endpoint, s3.REGION) */
    char bucket[256];
    char region[64];
    int sign; /* SigV4 with the credentials below */
    char key_id[256], secret[256], token[4096];
    char cred_from[128]; /* where the credentials came from (never the credentials) */
} bs_target;

/* Parses @p url (past bs_url_unprefix's prefixes) into @p t: http(s)://
 * (an S3 virtual-host or path-style address of amazonaws.com, or an address
 * under @p endpoint, is S3), s3://bucket/key (path-style under @p endpoint
 * when given, else the bucket's virtual host in the region), or
 * gs://bucket/key, read as https://storage.googleapis.com/bucket/key (or,
 * with STORAGE_EMULATOR_HOST set, as Google's client libraries do, under
 * that address). @p endpoint (AWS_ENDPOINT_URL) and
 * @p region (AWS_REGION) may be NULL. Credentials are not looked up here.
 * Errors: VV_ERR_INVALID (a malformed URL, naming it). */
vv_status bs_target_parse(bs_target *t, const char *url, const char *endpoint, const char *region);

/* The S3 credentials and region of the environment into @p t:
 * AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY, AWS_SESSION_TOKEN, else the
 * profile AWS_PROFILE (default "default") of AWS_SHARED_CREDENTIALS_FILE
 * (~/.aws/credentials) and AWS_CONFIG_FILE (~/.aws/config); none (or
 * AWS_NO_SIGN_REQUEST=YES): anonymous (t->sign 0). */
void bs_target_credentials(bs_target *t);

#endif
