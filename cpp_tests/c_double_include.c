/* Second translation unit for the C test: the header included twice, nothing else. */
#include "toothfuse.h"
#include "toothfuse.h"

int toothfuse_double_include_probe(void);

int toothfuse_double_include_probe(void) { return (int)toothfuse_abi_version(); }
