/* A process that streams through N MiB of memory forever, reading and writing every cache line:
 * the disturbance used in compressors/bicluster/README.md ("Row order") to test how the relights
 * stand a neighbour that evicts the shared L3 and takes memory bandwidth.
 *
 *   gcc -O2 -o /tmp/stream_hog scripts/stream_hog.c
 *   taskset -c 1 /tmp/stream_hog 256 &
 *   POCL_MAX_PTHREAD_COUNT=1 POCL_CPU_MAX_CU_COUNT=1 POCL_AFFINITY=1 taskset -c 0 \
 *     build/release/bench/relight_bench --benchmark_filter='(bicluster|uncompressed)/opencl'
 *   kill %1
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char** argv) {
  const long mib = argc > 1 ? atol(argv[1]) : 256;
  if (mib <= 0) {
    fprintf(stderr, "usage: %s MiB (a positive size)\n", argv[0]);
    return 2;
  }
  const size_t n = (size_t)mib << 20;
  unsigned char* p = malloc(n);
  if (!p) {
    fprintf(stderr, "%s: cannot allocate %ld MiB\n", argv[0], mib);
    return 1;
  }
  memset(p, 1, n);
  for (;;)
    for (size_t i = 0; i < n; i += 64) ++p[i];
}
