//! `memory-hints`: advice to the kernel and to the processor about memory that a loop reads in
//! random order: large blocks on transparent huge pages (2 MiB instead of 4 KiB) through a global
//! allocator, [`LargePages`], and a [`prefetch`] that asks for a cache line without waiting for it.
//!
//! It is the workspace's one crate with `unsafe` code: a global allocator and a prefetch
//! instruction cannot be had without it. Every unsafe block says why it is sound.
//!
//! **Why huge pages.** An event-driven simulation reads its bodies' records, event lists and
//! neighbour lists in the order the events come, which is random in memory. With 4 KiB pages the
//! processor's address-translation cache (the TLB, about 1 500 entries, so about 6 MiB of reach)
//! stops covering those arrays at about 10⁵ bodies, and then nearly every access pays a
//! page-table walk on top of its cache miss. With 2 MiB pages the same arrays need a few dozen
//! entries.
//!
//! On Linux, memory marked with `madvise(MADV_HUGEPAGE)` is backed by huge pages when the
//! kernel's transparent huge pages are set to `madvise` (a common default) or `always`; a plain
//! `malloc` gets them only under `always`. [`LargePages`] hands every request to the system
//! allocator. A request of at least [`HUGE_PAGE`] bytes is served from whole, aligned huge pages
//! (its size rounded up to a multiple of 2 MiB), marked before anything touches them. The advice
//! is only advice: where the kernel refuses it (huge pages off or not built in) the block is
//! ordinary memory and nothing fails. On other systems the blocks are only aligned.
//!
//! **Huge pages cost** memory: a large block takes up to 2 MiB more than it asks for (the last
//! huge page is whole), and growing or shrinking one copies it unless the rounded size stays the
//! same. Only 2 MiB-aligned stretches can be huge, so marking a block where the system allocator
//! happens to put it leaves up to 2 MiB at each end on small pages: in `dmd` with hard spheres at
//! N = 87 808 that took 1.08 of the CPU time of whole aligned pages, at 80 MiB instead of 96 MiB
//! of peak memory. Small requests are passed through untouched.
//!
//! **Prefetches** matter once the records no longer fit in the L2 cache: an event-driven loop
//! knows which records its next step reads (the next body's, its partners') before it reads
//! them. A load would wait for each miss and hold up the instructions behind it; a prefetch only
//! starts the transfer, and the loop goes on with the present event meanwhile.
//!
//! ```
//! #[global_allocator]
//! static ALLOCATOR: memory_hints::LargePages = memory_hints::LargePages;
//!
//! // Served from 2 MiB pages: 8 MiB of records read in random order.
//! let records = vec![0u64; 1 << 20];
//! assert_eq!(records.as_ptr() as usize % memory_hints::HUGE_PAGE, 0);
//!
//! // The record read next, asked for now.
//! memory_hints::prefetch(&records[123_456]);
//! ```

use std::alloc::{GlobalAlloc, Layout, System};

/// The size of a transparent huge page on x86-64 (and on 64-bit Arm with 4 KiB base pages):
/// requests at least this large start on and fill whole pages of this size.
pub const HUGE_PAGE: usize = 2 << 20;

/// The system allocator, with large blocks on huge pages (see the crate documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct LargePages;

/// The layout a request is served with: a large one is aligned to and rounded up to whole huge
/// pages; a small one (or one whose rounded size would not be a valid layout) as asked.
pub fn served(layout: Layout) -> Layout {
    if layout.size() < HUGE_PAGE {
        return layout;
    }
    layout
        .size()
        .checked_next_multiple_of(HUGE_PAGE)
        .and_then(|size| Layout::from_size_align(size, layout.align().max(HUGE_PAGE)).ok())
        .unwrap_or(layout)
}

/// Asks the kernel to back `[ptr, ptr + len)` with huge pages when it first touches them.
fn advise(ptr: *mut u8, len: usize) {
    #[cfg(target_os = "linux")]
    if !ptr.is_null() {
        // SAFETY: the range is a block this allocator has just obtained from the system allocator
        // and owns whole (it starts on a huge-page boundary, so on a base-page boundary as
        // madvise requires). MADV_HUGEPAGE changes only how the kernel backs the range, never
        // its contents or its mapping; a refusal (huge pages off) leaves ordinary memory.
        unsafe {
            libc::madvise(ptr.cast(), len, libc::MADV_HUGEPAGE);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (ptr, len);
}

// SAFETY: every block is obtained from `System` with the layout `served(layout)` and returned to
// it with the same (`served` is a pure function of the caller's layout, which the caller passes
// back unchanged), and that layout is at least as large and as aligned as the caller's.
unsafe impl GlobalAlloc for LargePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let served = served(layout);
        // SAFETY: `served` is no smaller than `layout`, whose size the caller guarantees non-zero.
        let ptr = unsafe { System.alloc(served) };
        if served != layout {
            advise(ptr, served.size());
        }
        ptr
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let served = served(layout);
        if served == layout {
            // SAFETY: as in `alloc`.
            return unsafe { System.alloc_zeroed(layout) };
        }
        // Marked before the zeroing touches the pages, so that they are huge from the start.
        // SAFETY: as in `alloc`.
        let ptr = unsafe { self.alloc(layout) };
        if !ptr.is_null() {
            // SAFETY: the block holds at least `layout.size()` writable bytes.
            unsafe { ptr.write_bytes(0, layout.size()) };
        }
        ptr
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with `served(layout)` (see the impl's comment).
        unsafe { System.dealloc(ptr, served(layout)) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller guarantees that `new_size`, rounded up to the alignment, does not
        // overflow `isize`, which is all a layout needs.
        let new_layout = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        let (old_served, new_served) = (served(layout), served(new_layout));
        if old_served == layout && new_served == new_layout {
            // Both small: the system allocator's own realloc.
            // SAFETY: the caller's guarantees, passed on unchanged.
            return unsafe { System.realloc(ptr, layout, new_size) };
        }
        if old_served == new_served {
            // The same whole huge pages still hold the block.
            return ptr;
        }
        // A new block, marked before the copy touches it; the old one is freed.
        // SAFETY: `new_layout` is valid and non-zero (the caller's guarantees).
        let new_ptr = unsafe { self.alloc(new_layout) };
        if !new_ptr.is_null() {
            // SAFETY: both blocks hold at least the smaller size and do not overlap (the old one
            // is still allocated); the old block is freed once, with the layout it came with.
            unsafe {
                std::ptr::copy_nonoverlapping(ptr, new_ptr, layout.size().min(new_size));
                self.dealloc(ptr, layout);
            }
        }
        new_ptr
    }
}

/// Asks the processor to bring the cache line holding `x` towards its L1 cache, without
/// waiting for it: unlike a load, a prefetch never holds up the instructions after it, so a loop
/// can ask for the records its next steps will read and go on working while they come.
#[inline(always)]
pub fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` is a hint: it reads nothing into registers, writes nothing and never
    // faults (here the address is even a live reference); it needs only SSE, which every x86-64
    // processor has.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn small_layouts_are_served_as_asked_and_large_ones_on_whole_huge_pages() {
        let small = Layout::from_size_align(HUGE_PAGE - 1, 8).unwrap();
        assert_eq!(served(small), small);
        let large = Layout::from_size_align(HUGE_PAGE + 1, 8).unwrap();
        let s = served(large);
        assert_eq!((s.size(), s.align()), (2 * HUGE_PAGE, HUGE_PAGE));
        let exact = Layout::from_size_align(3 * HUGE_PAGE, 4096).unwrap();
        assert_eq!(served(exact).size(), 3 * HUGE_PAGE);
        // A rounded size past isize::MAX is not a layout: served as asked (and then refused).
        let huge = Layout::from_size_align(isize::MAX as usize - 7, 8).unwrap();
        assert_eq!(served(huge), huge);
    }

    /// The flags of the mapping that holds `addr`, from `/proc/self/smaps`.
    #[cfg(target_os = "linux")]
    fn vm_flags(addr: usize) -> Option<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            let first = line.split_whitespace().next().unwrap_or("");
            if let Some((lo, hi)) = first.split_once('-')
                && let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
            {
                inside = (lo..hi).contains(&addr);
            } else if inside && let Some(flags) = line.strip_prefix("VmFlags:") {
                return Some(flags.trim().to_string());
            }
        }
        None
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_large_block_is_marked_for_huge_pages_and_a_small_one_is_not() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage/enabled").exists() {
            eprintln!("skipped: this kernel has no transparent huge pages");
            return;
        }
        // A process may have them switched off (prctl PR_SET_THP_DISABLE, inherited): the kernel
        // then refuses the advice, as it should.
        let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        if status
            .lines()
            .any(|l| l.split_whitespace().collect::<Vec<_>>() == ["THP_enabled:", "0"])
        {
            eprintln!("skipped: transparent huge pages are switched off for this process");
            return;
        }
        let large = Layout::from_size_align(3 * HUGE_PAGE + 12, 8).unwrap();
        let small = Layout::from_size_align(64 << 10, 8).unwrap();
        // SAFETY: non-zero layouts, freed below with the same layouts.
        let (big, little) = unsafe { (LargePages.alloc(large), LargePages.alloc(small)) };
        assert!(!big.is_null() && !little.is_null());
        assert_eq!(big as usize % HUGE_PAGE, 0);
        let big_flags = vm_flags(big as usize).expect("the block's mapping in smaps");
        let little_flags = vm_flags(little as usize).expect("the block's mapping in smaps");
        // SAFETY: allocated above with these layouts.
        unsafe {
            LargePages.dealloc(big, large);
            LargePages.dealloc(little, small);
        }
        assert!(
            big_flags.split_whitespace().any(|f| f == "hg"),
            "VmFlags of the large block: {big_flags}"
        );
        assert!(
            !little_flags.split_whitespace().any(|f| f == "hg"),
            "VmFlags of the small block: {little_flags}"
        );
    }

    #[test]
    fn a_prefetch_changes_nothing() {
        let records: Vec<u64> = (0..4096).collect();
        for r in records.iter().rev() {
            prefetch(r);
        }
        prefetch(&records);
        assert!(records.iter().enumerate().all(|(i, &r)| r == i as u64));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Growing, shrinking and zeroing across the huge-page threshold keep the contents, the
        /// alignment and the zeros.
        #[test]
        fn reallocations_keep_contents_and_alignment(
            sizes in prop::collection::vec(1usize..(5 * HUGE_PAGE), 1..6),
            align_log in 0u32..13,
            zeroed in any::<bool>(),
        ) {
            let align = 1usize << align_log;
            let mut layout = Layout::from_size_align(sizes[0], align).unwrap();
            // SAFETY: a non-zero layout; every block is freed or reallocated with its layout.
            let mut ptr = unsafe {
                if zeroed { LargePages.alloc_zeroed(layout) } else { LargePages.alloc(layout) }
            };
            prop_assert!(!ptr.is_null());
            if zeroed {
                // SAFETY: `ptr` holds `layout.size()` initialised (zeroed) bytes.
                let bytes = unsafe { std::slice::from_raw_parts(ptr, layout.size()) };
                prop_assert!(bytes.iter().all(|&b| b == 0));
            }
            let pattern = |i: usize| (i.wrapping_mul(2_654_435_761) >> 7) as u8;
            for i in 0..layout.size() {
                // SAFETY: in bounds of the block.
                unsafe { ptr.add(i).write(pattern(i)) };
            }
            for &new_size in &sizes[1..] {
                prop_assert_eq!(ptr as usize % align, 0);
                // SAFETY: `ptr` was allocated with `layout`; `new_size` is non-zero and small.
                let new_ptr = unsafe { LargePages.realloc(ptr, layout, new_size) };
                prop_assert!(!new_ptr.is_null());
                let kept = layout.size().min(new_size);
                // SAFETY: the first `kept` bytes were written and are preserved by realloc.
                let bytes = unsafe { std::slice::from_raw_parts(new_ptr, kept) };
                prop_assert!(bytes.iter().enumerate().all(|(i, &b)| b == pattern(i)));
                for i in kept..new_size {
                    // SAFETY: in bounds of the new block.
                    unsafe { new_ptr.add(i).write(pattern(i)) };
                }
                ptr = new_ptr;
                layout = Layout::from_size_align(new_size, align).unwrap();
            }
            prop_assert_eq!(ptr as usize % align, 0);
            // SAFETY: allocated (last) with `layout`.
            unsafe { LargePages.dealloc(ptr, layout) };
        }
    }
}
