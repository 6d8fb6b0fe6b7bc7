/*
 * test_output_plan.c — no output replaces an input (src/io/output_plan.h), without the command line: in a scratch
 * folder, an output that is an input by another spelling (./x, dir/../x, a hard link, a symbolic link) is refused
 * with a message naming both; a folder output holding an input and two outputs naming one file are refused; a new
 * output passes; missing folders are made (mkdir -p) and the empty ones removed again; a component that is a file
 * cannot be a folder; an empty plan passes.
 */
#include "io/output_plan.h" /* first: the header is self-contained */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "matremap.h"

#include "harness.h"

/* The scratch folder, made the working folder once, so that relative spellings ("./x") mean something. */
static void enter_scratch(void) {
    static int entered;
    if (entered) return;
    if (chdir(mr_test_scratch_dir()) != 0) {
        perror("chdir");
        exit(2);
    }
    entered = 1;
}

static int is_folder(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The plan's check: `expected` status, and every string of `words` (NULL-terminated) in the message. */
static int check_says(mr_output_plan *plan, mr_status expected, const char *const *words) {
    mr_clear_error();
    mr_status status = mr_output_plan_check(plan);
    int ok = status == expected;
    for (int k = 0; words != NULL && words[k] != NULL; k++) ok &= strstr(mr_last_error(), words[k]) != NULL;
    if (!ok) fprintf(stderr, "    got %s: '%s'\n", mr_status_str(status), mr_last_error());
    return ok;
}

MR_TEST(output_that_is_an_input_by_another_spelling_is_refused) {
    enter_scratch();
    MR_CHECK(mkdir("dir", 0777) == 0);
    MR_CHECK(mr_test_write_file("x.png", "x", 1));
    MR_CHECK(link("x.png", "hard.png") == 0);
    MR_CHECK(symlink("x.png", "soft.png") == 0);
    static const char *const spellings[] = {"x.png", "./x.png", "dir/../x.png", "hard.png", "soft.png"};
    for (size_t k = 0; k < sizeof spellings / sizeof spellings[0]; k++) {
        mr_output_plan plan = {0};
        MR_CHECK_OK(mr_output_plan_inputf(&plan, "x.png", "base_color=@%s", "x.png"));
        MR_CHECK_OK(mr_output_plan_output(&plan, spellings[k], k % 2 ? "-o out" : NULL));
        char expected[256];
        snprintf(expected, sizeof expected, "output '%s'%s is the input base_color=@x.png; refusing to overwrite it",
                 spellings[k], k % 2 ? " (-o out)" : "");
        const char *const words[] = {expected, NULL};
        MR_CHECK_MSG(check_says(&plan, MR_ERR_INVALID_ARG, words), "spelling %s", spellings[k]);
        MR_CHECK(strcmp(mr_last_error(), expected) == 0); // exactly the line the command line prints
        mr_output_plan_free(&plan);
    }
    // An unlabelled input is named by its path.
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_input(&plan, "./x.png", NULL));
    MR_CHECK_OK(mr_output_plan_output(&plan, "hard.png", NULL));
    const char *const words[] = {"output 'hard.png' is the input './x.png'; refusing to overwrite it", NULL};
    MR_CHECK(check_says(&plan, MR_ERR_INVALID_ARG, words));
    mr_output_plan_free(&plan);
    MR_CHECK(plan.inputs == NULL && plan.outputs == NULL && plan.input_count == 0); // freed: empty again
}

MR_TEST(folder_output_holding_an_input_is_refused) {
    enter_scratch();
    MR_CHECK(mkdir("rep", 0777) == 0 && mkdir("rep/sub", 0777) == 0);
    MR_CHECK(mr_test_write_file("rep/sub/env.hdr", "e", 1));
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_inputf(&plan, "rep/sub/env.hdr", "--env %s", "rep/sub/env.hdr"));
    MR_CHECK_OK(mr_output_plan_output_folder(&plan, "rep/", NULL));
    const char *const held[] = {"output folder 'rep/' holds the input --env rep/sub/env.hdr; refusing to replace it",
                                NULL};
    MR_CHECK(check_says(&plan, MR_ERR_INVALID_ARG, held));
    mr_output_plan_free(&plan);
    // The folder itself given as an input: "is the input".
    MR_CHECK_OK(mr_output_plan_input(&plan, "./rep", "the folder rep"));
    MR_CHECK_OK(mr_output_plan_output_folder(&plan, "rep", "-o rep"));
    const char *const is[] = {"output folder 'rep' (-o rep) is the input the folder rep; refusing to overwrite it",
                              NULL};
    MR_CHECK(check_says(&plan, MR_ERR_INVALID_ARG, is));
    mr_output_plan_free(&plan);
    // An input beside the folder, not in it: accepted.
    MR_CHECK(mr_test_write_file("rep_env.hdr", "e", 1));
    MR_CHECK_OK(mr_output_plan_input(&plan, "rep_env.hdr", "--env rep_env.hdr"));
    MR_CHECK_OK(mr_output_plan_output_folder(&plan, "rep", NULL));
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    mr_output_plan_free(&plan);
}

MR_TEST(two_outputs_naming_one_file_are_refused) {
    enter_scratch();
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_outputf(&plan, "pic_a.png", "-o %s", "pic_"));
    MR_CHECK_OK(mr_output_plan_output(&plan, "./pic_a.png", "--flags")); // neither exists yet
    const char *const words[] = {
        "output './pic_a.png' (--flags) is also the output 'pic_a.png' (-o pic_); refusing to write one over the other",
        NULL};
    MR_CHECK(check_says(&plan, MR_ERR_INVALID_ARG, words));
    mr_output_plan_free(&plan);
    // The same name in different folders: two files.
    MR_CHECK(mkdir("other", 0777) == 0);
    MR_CHECK_OK(mr_output_plan_output(&plan, "pic_a.png", NULL));
    MR_CHECK_OK(mr_output_plan_output(&plan, "other/pic_a.png", NULL));
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    mr_output_plan_free(&plan);
}

MR_TEST(new_output_is_accepted) {
    enter_scratch();
    MR_CHECK(mr_test_write_file("in.csv", "a", 1));
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_inputf(&plan, "in.csv", "sweep %s", "in.csv"));
    MR_CHECK_OK(mr_output_plan_input(&plan, NULL, "no file")); // a NULL path lists nothing
    MR_CHECK_OK(mr_output_plan_output(&plan, "new.mrt", NULL));
    MR_CHECK_OK(mr_output_plan_output(&plan, NULL, NULL));
    MR_CHECK(plan.input_count == 1 && plan.output_count == 1);
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    MR_CHECK(plan.folders_made_count == 0);
    mr_output_plan_free(&plan);
}

MR_TEST(missing_folders_are_made_and_the_empty_ones_unmade) {
    enter_scratch();
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_output(&plan, "a/b/c/x.png", NULL));
    MR_CHECK_OK(mr_output_plan_output(&plan, "a//d/y.png", NULL));
    MR_CHECK_OK(mr_output_plan_output_folder(&plan, "f/report/", NULL)); // its parent, not the folder itself
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    MR_CHECK(is_folder("a/b/c") && is_folder("a/d") && is_folder("f") && !is_folder("f/report"));
    MR_CHECK(plan.folders_made_count == 5); // a, a/b, a/b/c, a/d, f: parents first
    MR_CHECK(plan.folders_made_count == 5 && strcmp(plan.folders_made[0], "a") == 0 &&
             strcmp(plan.folders_made[2], "a/b/c") == 0 && strcmp(plan.folders_made[3], "a//d") == 0);
    // A second check makes nothing new.
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    MR_CHECK(plan.folders_made_count == 5);
    // Something written in a/b: a/b and a stay, the empty ones go.
    MR_CHECK(mr_test_write_file("a/b/kept.txt", "k", 1));
    mr_output_plan_unmake_folders(&plan);
    MR_CHECK(plan.folders_made_count == 0);
    MR_CHECK(!is_folder("a/b/c") && !is_folder("a/d") && !is_folder("f"));
    MR_CHECK(is_folder("a/b") && access("a/b/kept.txt", F_OK) == 0);
    mr_output_plan_free(&plan);

    // Taken by the caller: the plan forgets them, the caller owns the list.
    MR_CHECK_OK(mr_output_plan_output(&plan, "g/h/z.png", NULL));
    MR_CHECK(check_says(&plan, MR_OK, NULL));
    int count = -1;
    char **folders = mr_output_plan_take_folders(&plan, &count);
    MR_CHECK(count == 2 && folders != NULL && strcmp(folders[0], "g") == 0 && strcmp(folders[1], "g/h") == 0);
    MR_CHECK(plan.folders_made == NULL && plan.folders_made_count == 0);
    mr_output_plan_unmake_folders(&plan); // nothing left to unmake
    MR_CHECK(is_folder("g/h"));
    for (int k = count - 1; k >= 0; k--) {
        MR_CHECK(rmdir(folders[k]) == 0);
        free(folders[k]);
    }
    free(folders);
    MR_CHECK(mr_output_plan_take_folders(&plan, &count) == NULL && count == 0);
    mr_output_plan_free(&plan);
}

MR_TEST(file_in_the_way_of_a_folder_is_an_io_error) {
    enter_scratch();
    MR_CHECK(mr_test_write_file("plain", "p", 1));
    mr_output_plan plan = {0};
    MR_CHECK_OK(mr_output_plan_output(&plan, "plain/x/y.png", NULL));
    const char *const words[] = {"output 'plain/x/y.png': cannot create the folder 'plain': Not a directory", NULL};
    MR_CHECK(check_says(&plan, MR_ERR_IO, words));
    MR_CHECK(plan.folders_made_count == 0);
    mr_output_plan_free(&plan);
    // Folders made for an earlier output stay recorded when a later one fails.
    MR_CHECK_OK(mr_output_plan_output(&plan, "m/n/ok.png", NULL));
    MR_CHECK_OK(mr_output_plan_output(&plan, "plain/q.png", "--mask"));
    const char *const later[] = {"output 'plain/q.png' (--mask): cannot create the folder 'plain': Not a directory",
                                 NULL};
    MR_CHECK(check_says(&plan, MR_ERR_IO, later));
    MR_CHECK(plan.folders_made_count == 2 && is_folder("m/n"));
    mr_output_plan_unmake_folders(&plan);
    MR_CHECK(!is_folder("m"));
    mr_output_plan_free(&plan);
}

MR_TEST(empty_plan_checks_ok) {
    enter_scratch();
    mr_output_plan plan;
    memset(&plan, 0, sizeof plan);
    MR_CHECK_OK(mr_output_plan_check(&plan));
    MR_CHECK_OK(mr_output_plan_check(NULL));
    mr_output_plan_unmake_folders(&plan);
    mr_output_plan_unmake_folders(NULL);
    mr_output_plan_free(&plan);
    mr_output_plan_free(NULL);
    // Inputs only: nothing to refuse.
    MR_CHECK_OK(mr_output_plan_input(&plan, "nowhere.png", "base_color=@nowhere.png"));
    MR_CHECK_OK(mr_output_plan_check(&plan));
    mr_output_plan_free(&plan);
    // A registration that failed (out of memory) is reported by the next check, before any file is looked at.
    plan.out_of_memory = 1;
    const char *const words[] = {"out of memory listing the inputs and outputs", NULL};
    MR_CHECK(check_says(&plan, MR_ERR_NOMEM, words));
    mr_output_plan_free(&plan);
    MR_CHECK(plan.out_of_memory == 0);
}

MR_TEST_MAIN(MR_TEST_ENTRY(output_that_is_an_input_by_another_spelling_is_refused),
             MR_TEST_ENTRY(folder_output_holding_an_input_is_refused),
             MR_TEST_ENTRY(two_outputs_naming_one_file_are_refused), MR_TEST_ENTRY(new_output_is_accepted),
             MR_TEST_ENTRY(missing_folders_are_made_and_the_empty_ones_unmade),
             MR_TEST_ENTRY(file_in_the_way_of_a_folder_is_an_io_error), MR_TEST_ENTRY(empty_plan_checks_ok))
