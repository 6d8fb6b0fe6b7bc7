/*
 * cli.h — shared plumbing of the command-line front ends (the only code that prints or exits).
 *
 * Exit codes (docs/design.md): 0 ok, 1 usage error, 2 bad input (a file or value the user gave is wrong),
 * 3 internal or external failure. Messages go to stderr as "matremap CMD: error: what", results to stdout.
 */
#ifndef MR_CLI_H
#define MR_CLI_H

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

/* 1 if a and b name the same existing file (st_dev and st_ino: links, "./x" and other spellings included): an output
 * that would replace an input. */
int cli_same_file(const char *a, const char *b);

/* ---- what a command reads and writes: no output ever replaces an input (cli.c) ------------------------------
 * Every command that writes files lists its inputs (every file it reads: maps of name=@MAP, --env, datasets, the
 * files a glTF asset refers to, ...) and its outputs (every file it writes, derived names included: --loss-curve
 * PREFIX's PREFIX.csv and PREFIX.svg, --images PREFIX's pictures, a report's folder) and calls cli_io_check before
 * it writes anything; cli_io_check may be called again once more inputs are known (a glTF asset's files, after it
 * is read). An output is refused when it is the same file as an input: the same device and inode (stat), so "./x",
 * "dir/../x", hard links and symbolic links count; an output that does not exist yet, or lies in a folder that does
 * not, cannot be one. A folder output (cli_io_output_folder: report's folder, replaced as a whole) is refused when an
 * input lies inside it. Two outputs that name one file (the same existing file, or the same name in the same
 * existing folder) are refused too: the second would replace the first. The message names both arguments:
 *   matremap render: error: output 't.png' is the input base_color=@t.png; refusing to overwrite it
 *   matremap train: error: output 'ds.csv' (--loss-curve ds) is the input dataset ds.csv; refusing to overwrite it
 * and the exit code is 2 (bad input). Labels say how the user gave the file, as a noun phrase ("--env env.hdr",
 * "base_color=@t.png", "dataset ds.csv"); an output's label (may be NULL) says where a derived name comes from.
 * When every check passes, cli_io_check makes the missing folders the outputs are to be written in, nested as
 * mkdir -p does ("-o a/b/c/x.png" makes a, a/b and a/b/c; a folder output's parent, not the folder itself), so that
 * every command takes an output in a folder that does not exist yet, and says so before any work when it cannot:
 *   matremap render: error: output 'f/x/y.png': cannot create the folder 'f': Not a directory
 * (exit 2). A command that fails afterwards leaves none of the folders it made that are still empty (main.c calls
 * cli_io_unmake_folders on a non-zero exit code). */
typedef struct cli_io_entry {
    char *path;  /* owned copy */
    char *label; /* owned; NULL for an output named by itself */
    int folder;  /* output: a folder replaced as a whole */
} cli_io_entry;

typedef struct cli_io {
    const char *command;
    cli_io_entry *inputs, *outputs;
    int input_count, output_count, input_capacity, output_capacity;
    int out_of_memory; /* a registration failed: cli_io_check reports it (exit 3) */
} cli_io;

void cli_io_init(cli_io *io, const char *command);
/* Register an input file; the label is printf-formatted. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void cli_io_input(cli_io *io, const char *path, const char *label_fmt, ...);
/* Register an output file; label_fmt may be NULL (the path says it all: -o FILE). */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void cli_io_output(cli_io *io, const char *path, const char *label_fmt, ...);
/* Register an output folder, whose contents the command replaces as a whole. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void cli_io_output_folder(cli_io *io, const char *path, const char *label_fmt, ...);
/* Register the files of every name=@MAP[:c][:e] among a material's assignments (cli_material_load's syntax) as inputs,
 * labelled with the assignment as given (labels[k], or assignments[k] when labels is NULL). */
void cli_io_material(cli_io *io, const char *const *assignments, const char *const *labels, int count);
/* Register every file a glTF asset was read from (mr_gltf_source_file) as inputs: "<label>" for the asset's own file,
 * "a file of <label>" for its buffers and images. */
void cli_io_gltf(cli_io *io, const mr_gltf *asset, const char *label);
/* Parse "X,Y,Z" (three finite numbers, not all zero: a direction) given to `option`. 1, or 0 after a usage error
 * naming the option and the text. */
int cli_parse_direction(const char *command, const char *option, const char *text, double out[3]);
/* 1 if `text` names a glTF asset (ends in ".gltf" or ".glb"): what render and report take in a model's place. */
int cli_is_gltf_path(const char *text);
/* Read the glTF asset at `path`, note its files in io as inputs ("asset PATH"), check io again (an output over a
 * buffer or an image is refused, cli_io_check) and build its scene for the renderer (mr_gltf_scene_from_asset) into
 * *out (caller-owned). Returns a CLI exit code, after printing why when it is not CLI_EXIT_OK. */
struct mr_gltf_scene;
int cli_gltf_scene_load(const char *command, const char *path, cli_io *io, struct mr_gltf_scene **out);
/* CLI_EXIT_OK (the outputs' folders made), or print why (naming both files, or the folder that cannot be made) and
 * return CLI_EXIT_BAD_INPUT (CLI_EXIT_INTERNAL when a registration ran out of memory). Checks every pair each time it
 * is called. */
int cli_io_check(const cli_io *io);
void cli_io_free(cli_io *io);
/* Remove the folders cli_io_check made in this process that are still empty, deepest first. */
void cli_io_unmake_folders(void);

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

/* Parse "--hold NAME[,NAME...]": parameters of `model` to hold instead of fit (mr_remap_options.held); on an
 * unknown name print a usage error listing the model's parameters and return 0. */
int cli_parse_held(const char *command, const mr_brdf_model *model, const char *list, unsigned *held);

/* Write s as a JSON string literal (quotes and escapes included). */
void cli_json_string(FILE *out, const char *s);

/* Monotonic wall-clock seconds. */
double cli_now(void);

/* ---- text files the commands write themselves (cli_output.c) --------------------------------------------------
 * The library's atomic-file protocol (mr_core.h) with stdio: write into a temporary file beside the target,
 * rename it into place only when every write succeeded. A command writing several files prepares them all before
 * committing any, so a failure while writing leaves none of them. Each function prints its error as one line
 * "matremap CMD: error: ..." naming the file and the system's reason. */

/* The one rule for output names made from -o PREFIX (convert, spec2metal, metal2spec, remap --images): the library's
 * mr_img_prefixed_name (io/image_io.h), e.g. "avocado" + "basecolor.png" -> "avocado_basecolor.png", "out/" +
 * "alpha.exr" -> "out/alpha.exr". Writes the name into out (size bytes); returns 0 when it does not fit. */
int cli_output_name(char *out, size_t size, const char *prefix, const char *name);

/* Create the temporary file for `path` and open it for writing. NULL after printing the error. */
FILE *cli_output_open(const char *command, const char *path, mr_atomic_file *file);

/* Close f. 1 if every write to it succeeded (the temporary file then waits for mr_atomic_commit or
 * mr_atomic_commit_set); else 0, after printing the error and removing the temporary file. */
int cli_output_close(const char *command, FILE *f, mr_atomic_file *file);

/* ---- maps given on the command line: FILE[:r|g|b|a][:linear|srgb] (cli.c) ------------------------------------
 * Every command that reads a map of a parameter takes the file with optional selectors at its end, in this order:
 * a channel (:r, :g, :b or :a, where the command picks channels: a one-channel parameter of render, report and
 * convert), then an encoding (:linear or :srgb) that overrides the parameter's own (mr_img_read_param_map: 8/16-bit
 * colour maps sRGB, everything else linear; float files always linear, and :srgb on one is a usage error). E.g.
 * roughness=@orm.png:g:linear. Selectors are always taken from the end: a file whose own name ends in one is given
 * with an explicit encoding after it ("odd:linear:srgb" reads the file "odd:linear" as sRGB). */

/* Split `text` into its file and selectors: *path_length is the length of FILE at the start of text, *channel the
 * channel (0-3 for r, g, b, a; -1 when none is given or `channels` is 0: the command picks none, and ":g" stays part
 * of the file name), *encoding the override (MR_MAP_AS_PARAMETER when none is given). Never fails. */
void cli_split_map(const char *text, int channels, size_t *path_length, int *channel, mr_map_encoding *encoding);

/* A map's text split by cli_split_map, checked: CLI_EXIT_OK, or a usage error (CLI_EXIT_USAGE, printed with `label`,
 * how the user gave the map: "specular=@s.png:linear", "--specular s.png") for an empty file name, or for selectors
 * in the wrong order ("x.png:linear:g", when no file "x.png:linear" exists). */
int cli_check_map(const char *command, const char *label, const char *text, int channels);

/* Read the map in `text` (FILE[:c][:e], as cli_split_map takes it; the channel selector is the caller's to apply)
 * for parameter `param` (may be NULL: a map feeding no one parameter, linear unless overridden) with
 * mr_img_read_param_map (opts and stored as there). Returns a CLI exit code after printing any error naming `label`:
 * a usage error for a malformed map or :srgb on a float file, else cli_fail's. */
int cli_read_map(const char *command, const char *label, const char *text, int channels, const mr_brdf_param *param,
                 const mr_img_read_options *opts, mr_image **out, mr_img_stored *stored);

/* ---- materials on the command line: MODEL name=value ... name=@MAP[:r|g|b|a][:linear|srgb] ... (cli_material.c) */

#define CLI_MAX_ASSIGNMENTS 64

/* Build *out (an mr_material, render/render.h: mr_material_free) from MODEL and its assignments: values parsed,
 * maps read and bound. Returns a CLI exit code (messages printed, naming `command`); *out is NULL unless it is
 * CLI_EXIT_OK. */
int cli_material_load(const char *command, const char *model_name, const char *const *assignments, int count,
                      mr_material **out);
/* The commands that render a material's maps (render, report): one note on stderr per map holding texels that are
 * not parameter values, how many and how they are read (mr_material_map_invalid_texels, docs/rendering.md):
 * "matremap render: note: base_color=@nan.exr: 3 texels not finite, read as 0; 2 negative, clamped to 0". */
void cli_material_note_invalid_texels(const char *command, const mr_material *material);

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

#endif /* MR_CLI_H */
