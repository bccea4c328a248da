/* A qemu TCG plugin that counts the guest instructions a program executes.
 *
 * Each translation block gets one inline counter increment by its
 * instruction count when it is translated, so the count costs one add per
 * block executed (no callback). At exit the total goes to stderr, or to the
 * file named by the plugin argument outfile=PATH:
 *
 *   qemu-aarch64 -plugin ./libinsn_count.so,outfile=n.txt prog args
 *
 * The inline counter is one 64-bit integer shared by all guest threads:
 * exact for a single-threaded program. With the argument threads=on each
 * block calls back instead and the count is kept per guest thread (qemu-user
 * runs each on its own vCPU), atomically; the output then has a line
 * "thread N COUNT" for each thread that ran, in the order they started.
 * Built against qemu's own qemu-plugin.h, fetched by run.sh and never
 * stored in this repository. */
#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <qemu-plugin.h>

QEMU_PLUGIN_EXPORT int qemu_plugin_version = QEMU_PLUGIN_VERSION;

enum { kMaxThreads = 256 };
static uint64_t executed;
static uint64_t per_thread[kMaxThreads];
static bool by_thread;
static char outfile[4096];

static void on_execute(unsigned int vcpu, void* insns) {
  const uint64_t n = (uint64_t)(uintptr_t)insns;
  __atomic_fetch_add(&executed, n, __ATOMIC_RELAXED);
  if (vcpu < kMaxThreads) __atomic_fetch_add(&per_thread[vcpu], n, __ATOMIC_RELAXED);
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  const size_t n = qemu_plugin_tb_n_insns(tb);
  if (by_thread) {
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_execute, QEMU_PLUGIN_CB_NO_REGS,
                                         (void*)(uintptr_t)n);
  } else {
    qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &executed, n);
  }
}

static void report_at_exit(qemu_plugin_id_t id, void* unused) {
  (void)id;
  (void)unused;
  FILE* f = outfile[0] ? fopen(outfile, "w") : NULL;
  fprintf(f ? f : stderr, "instructions %" PRIu64 "\n", executed);
  for (int i = 0; by_thread && i < kMaxThreads; ++i)
    if (per_thread[i] != 0) fprintf(f ? f : stderr, "thread %d %" PRIu64 "\n", i, per_thread[i]);
  if (f) fclose(f);
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc,
                                           char** argv) {
  (void)info;
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "outfile=", 8) == 0 && strlen(argv[i] + 8) < sizeof outfile) {
      strcpy(outfile, argv[i] + 8);
    } else if (strcmp(argv[i], "threads=on") == 0) {
      by_thread = true;
    } else {
      fprintf(stderr, "insn_count: unknown argument '%s' (outfile=PATH, threads=on)\n", argv[i]);
      return -1;
    }
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
  qemu_plugin_register_atexit_cb(id, report_at_exit, NULL);
  return 0;
}
