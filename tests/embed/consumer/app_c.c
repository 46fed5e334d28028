/* The consumer test's C99 program: links the installed libstex through stex::stex, checks the ABI version
 * and the error path (a missing model file is STEX_INPUT with a message). Exit 0 on success. */
#include <stdio.h>
#include <stex/stex.h>
#include <string.h>

int main(void) {
  stex_model* model = NULL;
  stex_status status;
  if (stex_abi_version() != STEX_ABI_VERSION) {
    fprintf(stderr, "consumer_app_c: ABI %d, header %d\n", stex_abi_version(), STEX_ABI_VERSION);
    return 1;
  }
  status = stex_model_load("/nonexistent/model.stex", &model);
  if (status != STEX_INPUT || model != NULL || strstr(stex_last_error(), "model.stex") == NULL) {
    fprintf(stderr, "consumer_app_c: unexpected %s: %s\n", stex_status_name(status), stex_last_error());
    return 1;
  }
  printf("consumer_app_c: stex %s, ABI %d, error path ok (%s)\n", stex_version_string(), stex_abi_version(),
         stex_status_name(status));
  return 0;
}
