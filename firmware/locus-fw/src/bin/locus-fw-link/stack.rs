//! The stack high-water mark, as `locus-fw` measures it: paint the stack
//! below `main`'s frame at reset, find the lowest overwritten word after
//! the run.

/// Bytes of stack painted below `main`'s frame.
const PAINT_BYTES: usize = 32 * 1024;
/// Gap left unpainted just below the stack pointer while painting (the
/// painting code's own use).
const PAINT_GAP: usize = 256;
/// The paint pattern.
const PAINT: u32 = 0xDEAD_BEEF;

/// Paints the stack from `PAINT_BYTES` below the current stack pointer to
/// `PAINT_GAP` below it; returns the lowest painted address.
#[allow(unsafe_code)]
#[inline(always)]
pub fn paint() -> usize {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = sp - PAINT_BYTES;
    let mut a = bottom;
    while a < sp - PAINT_GAP {
        // SAFETY: the words between `bottom` and `sp - PAINT_GAP` are free
        // stack below the current frame (4 MiB of RAM, nothing else lives
        // there), written with volatile stores before any callee uses them.
        unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
        a += 4;
    }
    bottom
}

/// Bytes used from the top of the stack: from the lowest address above
/// `bottom` whose paint was overwritten; `None` if the paint at `bottom`
/// itself is gone (the stack went below the painted region).
#[allow(unsafe_code)]
pub fn high_water(bottom: usize) -> Option<usize> {
    let mut a = bottom;
    // SAFETY: reads of the painted region, which is ours.
    while unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
        a += 4;
    }
    (a != bottom).then(|| top() - a)
}

/// The top of the stack (`_stack_start` of cortex-m-rt's `link.x`).
#[allow(unsafe_code)]
fn top() -> usize {
    unsafe extern "C" {
        static _stack_start: u32;
    }
    // SAFETY: only the symbol's address is taken.
    (&raw const _stack_start) as usize
}
