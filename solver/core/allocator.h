#pragma once
// The process's heap policy for large short-lived arrays (ours, for speed).
//
// Every coupling pass builds arrays of tens to hundreds of MB and frees them (the loads'
// probes: 10 numbers per probe point, ≈ 100 MB at grid 1; the interpolations' sums; the loads).
// glibc serves arrays above its mmap threshold (≤ 32 MiB) with fresh mappings and unmaps them
// on free, so each pass page-faults through them again: at grid 1 the tight heart setting spent
// more than half of its time there (docs/benchmarks.md, "The heap policy": 2.0–2.9x faster
// without).
// keep_freed_memory_in_heap() makes glibc serve every allocation from its heap and never
// return freed memory to the system, so the arrays of one pass reuse the pages of the last.
//
// Contract: call once at the start of main, before any heavy allocation. Values are unchanged;
// only speed and memory residency change: the resident size stays at the process's peak
// (measured at grid 1: +2 % of the peak). Returns false if glibc refused a setting (the run then
// goes on with the default policy: slower, not different); the caller says so.
namespace systole {

bool keep_freed_memory_in_heap();

}  // namespace systole
