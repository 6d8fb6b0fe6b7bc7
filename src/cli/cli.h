/*
 * cli.h — shared plumbing of the command-line front ends (the only code that prints or exits).
 *
 * Exit codes (docs/design.md): 0 ok, 1 usage error, 2 bad input (a file or value the user gave is wrong),
 * 3 internal or external failure. Messages go to stderr as "matremap CMD: error: what", results to stdout.
 */
#ifndef MR_CLI_H
#define MR_CLI_H

#include <signal.h>
#include <stdio.h>

#include "matremap.h"

enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_USAGE = 1,
    CLI_EXIT_BAD_INPUT = 2,
    CLI_EXIT_INTERNAL = 3
};

/* The exit code for a failed library status: user-side failures are 2, the rest 3. */
int cli_exit_code(mr_status status);

/* Print "matremap CMD: error: <mr_last_error()>" and return cli_exit_code(status). */
int cli_fail(const char *command, mr_status status);

/* Print "matremap CMD: <message>" and a hint to --help on stderr; return CLI_EXIT_USAGE. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
int cli_usage_error(const char *command, const char *fmt, ...);

/* ---- what a command reads and writes: no output ever replaces an input (io/output_plan.h) --------------------
 * Every command that writes files lists its inputs (every file it reads: maps of name=@MAP, --env, datasets, the
 * files a glTF asset refers to, ...) and its outputs (every file it writes, derived names included: --loss-curve
 * PREFIX's PREFIX.csv and PREFIX.svg, --images PREFIX's pictures, a report's folder) in an mr_output_plan, labelled
 * as the user gave them ("--env env.hdr", "base_color=@t.png"; an output's label says where a derived name comes
 * from), and calls cli_plan_check before it writes anything, again once more inputs are known (a glTF asset's
 * files, after it is read). The library's header holds the contract: which outputs are refused, the messages, the
 * folders made (mkdir -p). Here a refused output or a folder that cannot be made exits 2, out of memory 3:
 *   matremap render: error: output 't.png' is the input base_color=@t.png; refusing to overwrite it
 *   matremap render: error: output 'f/x/y.png': cannot create the folder 'f': Not a directory
 * A command that fails afterwards leaves none of the folders it made that are still empty (main.c calls
 * cli_unmake_folders on a non-zero exit code). */

/* mr_output_plan_check, and the folders it made taken into the process's list (cli_unmake_folders): CLI_EXIT_OK, or
 * print "matremap CMD: error: <mr_last_error()>" and return cli_fail's exit code (CLI_EXIT_BAD_INPUT for a refused
 * output or a folder that cannot be made, CLI_EXIT_INTERNAL out of memory). */
int cli_plan_check(const char *command, mr_output_plan *plan);
/* Remove the folders cli_plan_check's plans made in this process that are still empty, deepest first. */
void cli_unmake_folders(void);
/* List the files of every name=@MAP[:c][:e] among a material's assignments (cli_material_load's syntax) as inputs,
 * labelled with the assignment as given (labels[k], or assignments[k] when labels is NULL). */
void cli_plan_material(mr_output_plan *plan, const char *const *assignments, const char *const *labels, int count);
/* List every file a glTF asset was read from (mr_gltf_source_file) as inputs: "<label>" for the asset's own file,
 * "a file of <label>" for its buffers and images. */
void cli_plan_gltf(mr_output_plan *plan, const mr_gltf *asset, const char *label);
/* Parse "X,Y,Z" (three finite numbers, not all zero: a direction) given to `option`. 1, or 0 after a usage error
 * naming the option and the text. */
int cli_parse_direction(const char *command, const char *option, const char *text, double out[3]);
/* 1 if `text` names a glTF asset (ends in ".gltf" or ".glb"): what render and report take in a model's place. */
int cli_is_gltf_path(const char *text);
/* Read the glTF asset at `path`, note its files in io as inputs ("asset PATH"), check io again (an output over a
 * buffer or an image is refused, cli_plan_check) and build its scene for the renderer (mr_gltf_scene_from_asset)
 * into *out (caller-owned). Returns a CLI exit code, after printing why when it is not CLI_EXIT_OK. */
struct mr_gltf_scene;
int cli_gltf_scene_load(const char *command, const char *path, mr_output_plan *io, struct mr_gltf_scene **out);

/* mr_image_check_radiance labelled "image 'PATH'": finite radiance >= 0 in the image read from `path`, or
 * MR_ERR_INVALID_ARG naming the file, the pixel, the channel and the value (measurements, environment maps). */
mr_status cli_check_radiance(const mr_image *image, const char *path);

/* True if argv[i] is "--help" or "-h". */
int cli_is_help(const char *arg);

/* Option matching for "--name VALUE" and "--name=VALUE": if argv[*i] is the option, store its value in
 * *value, advance *i past a separate value and return 1; return -1 (after printing a usage error) if the value
 * is missing; 0 if argv[*i] is another argument. */
int cli_take_option(const char *command, int argc, char **argv, int *i, const char *name, const char **value);

/* Parse an integer in [lo, hi]; on error print a usage error naming the option and return 0. */
int cli_parse_int(const char *command, const char *option, const char *text, int lo, int hi, int *out);

/* Parse a finite double in [lo, hi]; on error print a usage error naming the option and return 0. */
int cli_parse_double(const char *command, const char *option, const char *text, double lo, double hi,
                     double *out);

/* --convention gltf|paper (mr_wf_diffuse_from_name) into *out; 0 after a usage error naming `command`. */
int cli_parse_convention(const char *command, const char *value, mr_wf_diffuse *out);

/* Parse "--hold NAME[=VALUE][,NAME[=VALUE]...]" (mr_brdf_parse_holds): parameters of `model` to hold instead of fit
 * (mr_remap_options.held), a VALUE set in values[] (the target values the --to assignments filled); on an unknown
 * name or a bad value print a usage error naming it ("--hold: ...") and return 0. */
int cli_parse_held(const char *command, const mr_brdf_model *model, const char *list, double *values, unsigned *held);

/* The holds a fit of `model` used (mr_brdf_format_holds: the model's default holds and --hold's, with their values):
 * "held: LIST\n" on `out` (prefixed by `prefix`, e.g. "matremap convert: "; NULL: none), nothing when none. */
void cli_print_holds(FILE *out, const char *prefix, const mr_brdf_model *model, const double *values, unsigned held);
/* The same leaving out the parameters the fit tied instead (`tied`, mr_brdf_ties.tied; cli_print_ties says them). */
void cli_print_holds_tied(FILE *out, const char *prefix, const mr_brdf_model *model, const double *values,
                          unsigned held, unsigned tied);

/* The same as a JSON array (no key): [{"name": N, "value": V or [R, G, B], "by": "default" or "--hold"}, ...]. */
void cli_print_holds_json(FILE *out, const mr_brdf_model *model, const double *values, unsigned held, unsigned tied);

/* The ties of a fit (brdf.h): `list` (--tie TARGET=SOURCE,... or "none") parsed into *ties, or, when list is NULL,
 * the pair's defaults (mr_brdf_default_ties); parameters the caller holds (`held`, --hold) are not tied (a hold
 * wins). Returns 1, or prints a usage error naming the item and returns 0. */
int cli_parse_ties(const char *command, const mr_brdf_model *source, const mr_brdf_model *target, const char *list,
                   unsigned held, mr_brdf_ties *ties);
/* "PREFIXtied: base_metalness=metallic (default for gltf -> openpbr)" ("(--tie)" when given); nothing for none. */
void cli_print_ties(FILE *out, const char *prefix, const mr_brdf_model *source, const mr_brdf_model *target,
                    const mr_brdf_ties *ties, int given);
/* The same as a JSON array: [{"name": T, "source": S, "by": "default" or "--tie"}, ...]. */
void cli_print_ties_json(FILE *out, const mr_brdf_model *source, const mr_brdf_model *target,
                         const mr_brdf_ties *ties, int given);

/* Write s as a JSON string literal (quotes and escapes included). */
void cli_json_string(FILE *out, const char *s);

/* Monotonic wall-clock seconds. */
double cli_now(void);

/* ---- text files the commands write themselves (cli_output.c) --------------------------------------------------
 * The library's atomic-file protocol (mr_core.h) with stdio: write into a temporary file beside the target,
 * rename it into place only when every write succeeded. A command writing several files prepares them all before
 * committing any, so a failure while writing leaves none of them. Each function prints its error as one line
 * "matremap CMD: error: ..." naming the file and the system's reason. */

/* Create the temporary file for `path` and open it for writing. NULL after printing the error. */
FILE *cli_output_open(const char *command, const char *path, mr_atomic_file *file);

/* Close f. 1 if every write to it succeeded (the temporary file then waits for mr_atomic_commit or
 * mr_atomic_commit_set); else 0, after printing the error and removing the temporary file. */
int cli_output_close(const char *command, FILE *f, mr_atomic_file *file);

/* ---- materials on the command line: MODEL name=value ... name=@MAP[:r|g|b|a][:linear|srgb] ... (cli_material.c) */

#define CLI_MAX_ASSIGNMENTS 64

/* Build *out (an mr_material, render/render.h: mr_material_free) from MODEL and its assignments
 * (mr_material_from_assignments: values parsed, maps read and bound). Returns a CLI exit code (messages printed,
 * naming `command`: a usage error when the text is at fault, else cli_fail's); *out is NULL unless it is
 * CLI_EXIT_OK. */
int cli_material_load(const char *command, const char *model_name, const char *const *assignments, int count,
                      mr_material **out);
/* The commands that render a material's maps (render, report): one note on stderr per map holding texels that are
 * not parameter values, how many and how they are read (mr_material_describe_invalid_texels, docs/rendering.md):
 * "matremap render: note: base_color=@nan.exr: 3 texels not finite, read as 0; 2 negative, clamped to 0". */
void cli_material_note_invalid_texels(const char *command, const mr_material *material);

/* ---- renderers on either side of a remap (cli_renderer.c) ---- */

/* --from-renderer NAME, --to-renderer NAME, --samples N of remap, sweep and report, and what they opened. */
typedef struct cli_renderers {
    const char *names[2];     /* source, target: NULL = builtin */
    int samples;              /* 0: the renderers' defaults */
    unsigned long seed;       /* the path tracers' seed: 0 */
    mr_renderer *opened[2];   /* NULL: built-in */
    char versions[2][128];    /* "blender 3.4.1" once started */
} cli_renderers;

/* The options above' help lines, for a command's --help. */
void cli_renderers_help(FILE *out);
/* Take argv[*i] if it is one of the options: 1 taken, -1 after a usage error, 0 another argument. */
int cli_take_renderer_option(const char *command, int argc, char **argv, int *i, cli_renderers *r);
/* Check that each side's renderer renders its model by values (source NULL: a material of the renderer's own),
 * then open and start the external ones (`processes` each, 0 = the thread rule): CLI_EXIT_OK or the exit code
 * after the message (a missing Blender: exit 3 naming the package). */
int cli_open_renderers(const char *command, cli_renderers *r, const mr_brdf_model *source,
                       const mr_brdf_model *target, int processes);
void cli_close_renderers(cli_renderers *r);
/* "renderers: source blender 3.4.1 (256 samples, N renders), target builtin\n"; JSON: the object's text. */
void cli_print_renderers(FILE *out, const cli_renderers *r);
void cli_print_renderers_json(FILE *out, const cli_renderers *r);
/* 'NODE.SOCKET=v' or 'NODE.SOCKET=r,g,b' set on a renderer's own material (the path may hold spaces and dots: split
 * at the last '='): CLI_EXIT_OK, or the exit code after the message. */
int cli_set_material_input(const char *command, mr_external_material *material, const char *assignment);
/* The material's inputs as a JSON object {"PATH": value or [r, g, b], ...}. */
void cli_print_material_inputs_json(FILE *out, const mr_external_material *material);

/* ---- many items (cli_library.c) ---- */

/* --shard K/N (0 <= K < N <= max) into *k, *n; 0 after a usage error naming `command`. */
int cli_parse_shard(const char *command, const char *text, long max, long *k, long *n);

/* How a many-asset run shows its progress (mr_gltf_library_options.progress = cli_library_progress, progress_user =
 * a cli_library_view): on a terminal a bar on stderr (assets done/total, texels per second, time left), otherwise a
 * line per finished asset on stdout, a converted one named with done_word ("exported"; NULL: its status). */
typedef struct cli_library_view {
    int tty;
    const char *done_word;
} cli_library_view;
void cli_library_progress(void *user, const mr_gltf_library_progress *p);

/* SIGINT and SIGTERM set the returned flag (mr_gltf_library_options.cancel) until cli_library_cancel_end restores
 * the handlers saved in old[2]. */
volatile sig_atomic_t *cli_library_cancel_begin(struct sigaction old[2]);
void cli_library_cancel_end(const struct sigaction old[2]);
/* The end of a many-asset run: the failed assets named on stderr ("matremap COMMAND: ASSET failed: why"), then
 * one JSON object ({JSON_HEAD, "output": ..., "assets": N, "DONE_WORD": N, ...}) or the summary line ("matremap
 * LABEL: N assets: N DONE_WORD, ..."); frees *r. The exit code: the library's failure, else 2 when an asset failed. */
int cli_library_report(const char *command, const char *label, const char *json_head, const char *done_word,
                       const char *output, int json, mr_status status, mr_gltf_library_result *r);

int cmd_models(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_ssim(int argc, char **argv);
int cmd_remap(int argc, char **argv);
int cmd_sweep(int argc, char **argv);
int cmd_dataset(int argc, char **argv);
int cmd_train(int argc, char **argv);
int cmd_learn(int argc, char **argv);
int cmd_convert(int argc, char **argv);
int cmd_spec2metal(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_gltf(int argc, char **argv);
int cmd_metal2spec(int argc, char **argv);
int cmd_export(int argc, char **argv);

#endif /* MR_CLI_H */
