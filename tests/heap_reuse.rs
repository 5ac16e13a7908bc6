//! `HeapReuse` keeps freed memory in the process while alive, so that a
//! block allocated after another was freed reuses its pages instead of
//! faulting in fresh ones, and gives it back when it ends. Page faults are
//! counted by the kernel (`getrusage`), so this is an observation of the
//! C allocator's behaviour, not of our own bookkeeping; it has its own
//! test binary so that no other test allocates meanwhile.

#![cfg(all(target_os = "linux", target_env = "gnu"))]

use aerial::mesh::heap::HeapReuse;

/// Minor page faults of this process so far.
fn faults() -> i64 {
    // SAFETY: `usage` is a valid, writable rusage for the call to fill.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    usage.ru_minflt
}

/// Page faults taken while allocating and writing a block of `bytes`,
/// after a block of the same size was allocated, written and freed.
fn faults_of_second_block(bytes: usize) -> i64 {
    let first = vec![1u8; bytes];
    std::hint::black_box(&first);
    drop(first);
    let before = faults();
    let second = vec![2u8; bytes];
    std::hint::black_box(&second);
    let taken = faults() - before;
    drop(second);
    taken
}

#[test]
fn freed_blocks_are_reused_while_a_guard_lives_and_returned_after() {
    // 48 MiB: above every threshold the allocator picks by itself (32 MiB
    // at most), so by default it is mapped and unmapped each time; and
    // below the 64 MiB of a thread's own heap (tests run on threads other
    // than the main one), past which a block is always mapped.
    const BYTES: usize = 48 << 20;
    let pages = (BYTES / 4096) as i64;

    let fresh = faults_of_second_block(BYTES);
    assert!(
        fresh > pages / 2,
        "by default a large block is fresh memory: {fresh} faults for {pages} pages"
    );

    let outer = HeapReuse::enter();
    // Warm the heap to the block's size once, then measure the reuse.
    faults_of_second_block(BYTES);
    let reused = faults_of_second_block(BYTES);
    {
        // Guards nest: an inner one ending keeps the policy.
        let inner = HeapReuse::enter();
        drop(inner);
    }
    let reused_after_inner = faults_of_second_block(BYTES);
    drop(outer);
    assert!(
        reused < pages / 20 && reused_after_inner < pages / 20,
        "with a guard the second block reuses the first's pages: {reused} and \
         {reused_after_inner} faults for {pages} pages"
    );

    // The policy ended with the last guard: large blocks are fresh again.
    let fresh_again = faults_of_second_block(BYTES);
    assert!(
        fresh_again > pages / 2,
        "after the last guard a large block is fresh memory again: {fresh_again} \
         faults for {pages} pages"
    );
}
