/*
 * volvis renderers [NAME] [--json]: the registry's renderers, what they
 * draw (object kinds, modes), their capabilities and their typed options,
 * read from the one table every caller uses (include/volvis/render.h). The
 * JSON form is for scripts and tests: every option with its type, default,
 * range, words and one-line documentation. The gpu renderer's Vulkan
 * devices follow it (vv_gpu_devices), numbered as its option `device`.
 */
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static const cli_opt_spec renderers_opts[] = {{"json", 0, NULL}};

void
cli_renderers_usage(FILE *out) {
    fprintf(out, "usage: volvis renderers [NAME] [--json]\n"
                 "\n"
                 "Lists the rendering methods built in (or only NAME): what each draws\n"
                 "(object kinds and modes), whether it renders regions (out of core with\n"
                 "--memory-limit, distributed under mpirun), what --quality means to it, and\n"
                 "its options for 'volvis render --set KEY=VALUE' with their types, defaults\n"
                 "and ranges. Without --renderer, 'volvis render' takes the scene's\n"
                 "renderer, else the first in this list that draws every object of the\n"
                 "World.\n"
                 "\n"
                 "After the gpu renderer come the Vulkan devices it can run on, numbered\n"
                 "as its option device (--set device=N): a GPU, or a CPU device such as\n"
                 "Mesa's lavapipe; or why there is none (no loader, no driver).\n"
                 "\n"
                 "Options:\n"
                 "  --json      one JSON document: {\"renderers\": [{\"name\", \"description\",\n"
                 "              \"draws\": [kinds], \"modes\": [modes], \"capabilities\": [...],\n"
                 "              \"quality\", \"options\": [{\"key\", \"type\", \"default\",\n"
                 "              \"min\", \"max\", \"min_open\", \"max_open\", \"values\",\n"
                 "              \"accepts\", \"doc\"}]}], \"gpu_devices\": [{\"index\",\n"
                 "              \"name\", \"kind\", \"cpu\", \"memory_bytes\"}],\n"
                 "              \"gpu_unavailable\": why, when none}\n"
                 "  -h, --help  show this help\n"
                 "\n"
                 "Examples:\n"
                 "  volvis renderers\n"
                 "  volvis renderers raytrace --json\n");
}

static const char *const cap_names[] = {"region",      "quality", "preview",
                                        "progressive", "global",  "channels"};

static json_t *
option_json(const vv_option_spec *o) {
    json_t *j = json_object();
    char what[256];
    json_object_set_new(j, "key", json_string(o->key));
    json_object_set_new(j, "type", json_string(vv_option_type_name(o->type)));
    json_object_set_new(j, "default", json_string(o->def));
    if (o->type == VV_OPTION_INT || o->type == VV_OPTION_REAL) {
        /* JSON has no infinity: an unbounded end is null */
        json_object_set_new(j, "min", isfinite(o->min) ? json_real(o->min) : json_null());
        json_object_set_new(j, "max", isfinite(o->max) ? json_real(o->max) : json_null());
        json_object_set_new(j, "min_open", json_boolean(o->flags & VV_OPTION_MIN_OPEN));
        json_object_set_new(j, "max_open", json_boolean(o->flags & VV_OPTION_MAX_OPEN));
    }
    json_t *words = json_array();
    for (int i = 0; o->words && o->words[i]; i++)
        json_array_append_new(words, json_string(o->words[i]));
    json_object_set_new(j, "values", words);
    json_object_set_new(j, "accepts", json_string(vv_option_describe(o, what, sizeof what)));
    json_object_set_new(j, "doc", json_string(o->doc));
    return j;
}

static json_t *
renderer_json(const vv_renderer_info *in) {
    json_t *j = json_object();
    json_object_set_new(j, "name", json_string(in->name));
    json_object_set_new(j, "description", json_string(in->description));
    json_t *draws = json_array(), *modes = json_array(), *caps = json_array();
    for (int t = 0; t <= VV_OBJECT_GRID; t++)
        if (in->draws & VV_DRAWS(t))
            json_array_append_new(draws, json_string(vv_object_type_name((vv_object_type)t)));
    char buf[128];
    cli_renderer_modes(in->modes, buf, sizeof buf);
    for (char *m = strtok(buf, ", "); m; m = strtok(NULL, ", "))
        json_array_append_new(modes, json_string(m));
    for (unsigned b = 0; b < sizeof cap_names / sizeof cap_names[0]; b++)
        if (in->caps & (1u << b))
            json_array_append_new(caps, json_string(cap_names[b]));
    json_object_set_new(j, "draws", draws);
    json_object_set_new(j, "modes", modes);
    json_object_set_new(j, "capabilities", caps);
    json_object_set_new(j, "quality", json_string(in->quality));
    json_t *opts = json_array();
    for (int k = 0; k < in->n_options; k++)
        json_array_append_new(opts, option_json(&in->options[k]));
    json_object_set_new(j, "options", opts);
    return j;
}

static void
print_text(const vv_renderer_info *in) {
    char kinds[256], modes[128], what[256];
    printf("%s: %s\n", in->name, in->description);
    printf("  draws:        %s\n", cli_renderer_kinds(in->draws, kinds, sizeof kinds));
    printf("  modes:        %s\n", cli_renderer_modes(in->modes, modes, sizeof modes));
    printf("  capabilities:");
    int any = 0;
    for (unsigned b = 0; b < sizeof cap_names / sizeof cap_names[0]; b++)
        if (in->caps & (1u << b)) {
            printf("%s %s", any ? "," : "", cap_names[b]);
            any = 1;
        }
    printf("%s\n", any ? "" : " none");
    printf("  quality:      %s\n", in->quality);
    if (!in->n_options)
        printf("  options:      none\n");
    for (int k = 0; k < in->n_options; k++) {
        const vv_option_spec *o = &in->options[k];
        printf("  --set %s=%s (default %s)\n      %s\n", o->key,
               vv_option_describe(o, what, sizeof what), o->def[0] ? o->def : "none", o->doc);
    }
}

/* The gpu renderer's devices, after its entry (text) or as "gpu_devices". */
static void
print_gpu_devices(json_t *root) {
    vv_gpu_device d[16];
    const char *why = NULL;
    const int n = vv_gpu_devices(d, 16, &why);
    json_t *list = root ? json_array() : NULL;
    for (int i = 0; i < n && i < 16; i++) {
        const double gib = (double)d[i].memory_bytes / (1024.0 * 1024.0 * 1024.0);
        if (root)
            json_array_append_new(list, json_pack("{s:i, s:s, s:s, s:b, s:I}", "index", i, "name",
                                                  d[i].name, "kind", d[i].kind, "cpu", d[i].cpu,
                                                  "memory_bytes", (json_int_t)d[i].memory_bytes));
        else
            printf("  device %d:     %s (%s, %.1f GiB)%s\n", i, d[i].name, d[i].kind, gib,
                   d[i].cpu ? "; a CPU device: the GUI does not pick it on its own" : "");
    }
    if (root) {
        json_object_set_new(root, "gpu_devices", list);
        if (n == 0)
            json_object_set_new(root, "gpu_unavailable", json_string(why ? why : "none"));
    } else if (n == 0) {
        printf("  devices:      none: %s\n", why ? why : "none found");
    }
}

int
cli_renderers_main(int argc, char **argv) {
    cli_args a;
    int rc = cli_parse(&a, "renderers", renderers_opts,
                       (int)(sizeof renderers_opts / sizeof renderers_opts[0]), argc, argv);
    if (rc == CLI_HELP) {
        cli_renderers_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (rc)
        return rc;
    if (a.n_pos > 1)
        return cli_usage_error(&a, "expected at most one NAME, got %d arguments", a.n_pos);
    const vv_renderer_info *only = NULL;
    if (a.n_pos == 1 && !(only = vv_renderer_info_find(a.pos[0]))) {
        char names[512];
        return cli_usage_error(&a, "unknown renderer '%s' (available: %s)", a.pos[0],
                               cli_renderer_names(names, sizeof names));
    }
    const int json = cli_count(&a, "json") > 0;
    json_t *root = json ? json_object() : NULL, *list = json ? json_array() : NULL;
    for (int i = 0; i < vv_renderer_count(); i++) {
        const vv_renderer_info *in = vv_renderer_info_at(i);
        if (only && in != only)
            continue;
        if (json)
            json_array_append_new(list, renderer_json(in));
        else
            print_text(in);
        if (!json && !strcmp(in->name, "gpu"))
            print_gpu_devices(NULL);
    }
    if (json) {
        json_object_set_new(root, "renderers", list);
        if (!only || !strcmp(only->name, "gpu"))
            print_gpu_devices(root);
        char *text = json_dumps(root, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
        json_decref(root);
        if (!text) {
            cli_error("renderers: out of memory");
            return CLI_EXIT_FAIL;
        }
        printf("%s\n", text);
        free(text);
    }
    return CLI_EXIT_OK;
}
