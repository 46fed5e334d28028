// One entry point per fuzz target (issue #12): the code a libFuzzer target runs on each input, shared with
// the regression replay test (tests/hardening/test_fuzz_regressions.cpp), which runs every corpus and
// regression file through the same function in the normal build. Each function swallows stex::Error (the
// documented way to reject an input) and checks the invariants of an accepted input; anything else
// (another exception, a broken invariant: std::abort) is a finding.
#pragma once
#include <cstddef>
#include <cstdint>

namespace stex::fuzz {

// decode_model on the bytes; an accepted model has a consistent shape and finite values.
void model_file_one(const std::uint8_t* data, std::size_t size);
// load_exemplar on the bytes written to a per-process temp file (pixel budget 2^20, the normal allow-list);
// an accepted image has its declared size, within the budget, and finite values.
void exemplar_one(const std::uint8_t* data, std::size_t size);
// parse_tile_spec on the bytes after a 5-byte grid prefix (width, height <= 256, tile size <= 256); an
// accepted selection is sorted, unique, inside the grid, and format_index_list of it parses back to it.
void tile_spec_one(const std::uint8_t* data, std::size_t size);
// NameTemplate on the bytes; an accepted template formats the tiles of a small grid when check_grid
// accepts it, and distinct tiles get distinct names then.
void name_template_one(const std::uint8_t* data, std::size_t size);

}  // namespace stex::fuzz
