//! A worker that dies of a fault says where, in one stderr line, before the signal kills it.
//!
//! "The worker died: signal 7 (SIGBUS)" does not say whose bug it is. The kernel knows more,
//! and tells only the process: the signal's code and the address it faulted on. This module
//! installs a handler for SIGSEGV, SIGBUS, SIGILL and SIGFPE in the worker that writes
//!
//! ```text
//! umbra: fatal SIGBUS (BUS_ADRERR: the address has no backing: a mapped file cut short, a full tmpfs) at 0x7f…: in /home/u/.cache/mesa_shader_cache/index (file offset 0x…); instruction 0x7f… in /usr/lib/x86_64-linux-gnu/libvulkan_lvp.so+0x1a2b3c
//! ```
//!
//! and then lets the signal take its course (the previous handler, Rust's stack-overflow
//! check, runs next; then the default action), so the worker still dies by the same signal
//! and the run is the same Crash, now with its last stderr line ([`super::scheduler`]) naming
//! the mapping the address lies in and the library and offset of the faulting instruction:
//! what `addr2line -e LIB 0xOFFSET` needs, and what tells a file-backed SIGBUS (BUS_ADRERR
//! in a file: whoever shortened the file) from a wild pointer (SI_KERNEL: a non-canonical
//! address, memory corruption in the process).
//!
//! The handler is async-signal-safe: no allocation, no lock, only `open`, `read`, `write`
//! and `close` (signal-safety(7)); `/proc/self/maps` is read line by line into fixed buffers.
//! Those buffers are one static [`Scratch`], taken by the first fault (a second thread
//! faulting meanwhile skips the line and dies as it would have), not the stack: the handler
//! runs on the thread's alternate signal stack where Rust set one (`SA_ONSTACK`), and that
//! stack is SIGSTKSZ (8 KiB), of which the kernel's saved register state takes up to 3 KiB
//! on an AVX-512 machine. With 5 KiB of buffers on it the handler overflowed it and the
//! worker died of SIGSEGV in the reporter, not of the signal it reported.
#![allow(unsafe_code)] // sigaction(2) and the handler's system calls: each block says why it holds.

use std::sync::atomic::{AtomicBool, Ordering};

/// The signals reported.
const SIGNALS: [libc::c_int; 4] = [libc::SIGSEGV, libc::SIGBUS, libc::SIGILL, libc::SIGFPE];

/// The handlers that were there before ours (Rust's stack-overflow check for SIGSEGV and
/// SIGBUS), one per [`SIGNALS`] entry, put back when ours has written its line.
static mut PREVIOUS: [std::mem::MaybeUninit<libc::sigaction>; 4] =
    [const { std::mem::MaybeUninit::zeroed() }; 4];

static INSTALLED: AtomicBool = AtomicBool::new(false);

/// Set by the first fault to take [`SCRATCH`]; never cleared (the process is dying).
static TAKEN: AtomicBool = AtomicBool::new(false);

/// The buffers `/proc/self/maps` is read through, off the (small) signal stack.
static mut SCRATCH: Scratch = Scratch::new();

/// Fixed buffers for [`scan`]: a chunk of the file and the line being assembled.
struct Scratch {
    chunk: [u8; 4096],
    text: [u8; 512],
}

impl Scratch {
    const fn new() -> Scratch {
        Scratch {
            chunk: [0; 4096],
            text: [0; 512],
        }
    }
}

/// Installs the reporter in this process (once; later calls do nothing).
pub fn install() {
    if INSTALLED.swap(true, Ordering::SeqCst) {
        return;
    }
    for (i, &sig) in SIGNALS.iter().enumerate() {
        // SAFETY: a zeroed sigaction is valid; the handler has the SA_SIGINFO signature;
        // PREVIOUS is written here, before any handler can read it, and only once.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = handler as *const () as libc::sighandler_t;
            action.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
            libc::sigemptyset(&mut action.sa_mask);
            let previous = (&raw mut PREVIOUS[i]).cast::<libc::sigaction>();
            libc::sigaction(sig, &action, previous);
        }
    }
}

extern "C" fn handler(sig: libc::c_int, info: *mut libc::siginfo_t, context: *mut libc::c_void) {
    if !TAKEN.swap(true, Ordering::SeqCst) {
        let scratch: *mut Scratch = &raw mut SCRATCH;
        // SAFETY: TAKEN was clear, so this is the only handler that will ever hold SCRATCH.
        let scratch = unsafe { &mut *scratch };
        report(sig, info, context, scratch);
    }
    // Put the earlier handler back and return: the instruction faults again, and that
    // handler (or the default action) ends the process by the same signal.
    if let Some(i) = SIGNALS.iter().position(|&s| s == sig) {
        // SAFETY: PREVIOUS[i] was filled by `install` before this handler could run.
        unsafe {
            let previous = (&raw const PREVIOUS[i]).cast::<libc::sigaction>();
            libc::sigaction(sig, previous, std::ptr::null_mut());
        }
    }
}

/// Writes the fault's line to stderr.
fn report(
    sig: libc::c_int,
    info: *mut libc::siginfo_t,
    context: *mut libc::c_void,
    scratch: &mut Scratch,
) {
    let mut line = Line::new();
    line.push(b"umbra: fatal ");
    line.push(signal_name(sig));
    // SAFETY: the kernel passes a valid siginfo_t and ucontext_t to an SA_SIGINFO handler.
    let (code, addr) = unsafe { ((*info).si_code, (*info).si_addr() as usize) };
    line.push(b" (");
    line.push(code_name(sig, code));
    line.push(b") at ");
    line.hex(addr);
    line.push(b": ");
    where_is(&mut line, addr, true, scratch);
    if let Some(pc) = instruction(context) {
        line.push(b"; instruction ");
        line.hex(pc);
        line.push(b" ");
        where_is(&mut line, pc, false, scratch);
    }
    line.push(b"\n");
    // SAFETY: write(2) on a stack buffer is async-signal-safe.
    unsafe {
        libc::write(2, line.bytes.as_ptr().cast(), line.len);
    }
}

/// The faulting instruction's address, from the signal's saved registers.
fn instruction(context: *mut libc::c_void) -> Option<usize> {
    if context.is_null() {
        return None;
    }
    #[cfg(all(target_arch = "x86_64", target_os = "linux"))]
    {
        // SAFETY: an SA_SIGINFO handler's third argument is the interrupted ucontext_t.
        let uc = unsafe { &*context.cast::<libc::ucontext_t>() };
        Some(uc.uc_mcontext.gregs[libc::REG_RIP as usize] as usize)
    }
    #[cfg(all(target_arch = "aarch64", target_os = "linux"))]
    {
        // SAFETY: as above.
        let uc = unsafe { &*context.cast::<libc::ucontext_t>() };
        Some(uc.uc_mcontext.pc as usize)
    }
    #[cfg(not(all(
        any(target_arch = "x86_64", target_arch = "aarch64"),
        target_os = "linux"
    )))]
    {
        None
    }
}

fn signal_name(sig: libc::c_int) -> &'static [u8] {
    match sig {
        libc::SIGSEGV => b"SIGSEGV",
        libc::SIGBUS => b"SIGBUS",
        libc::SIGILL => b"SIGILL",
        libc::SIGFPE => b"SIGFPE",
        _ => b"signal",
    }
}

/// The signal's code, named with what it means for whose fault it is (sigaction(2)).
fn code_name(sig: libc::c_int, code: libc::c_int) -> &'static [u8] {
    const SI_KERNEL: libc::c_int = 0x80;
    match (sig, code) {
        (libc::SIGBUS, 1) => b"BUS_ADRALN: a misaligned access",
        (libc::SIGBUS, 2) => {
            b"BUS_ADRERR: the address has no backing: a mapped file cut short, a full tmpfs"
        }
        (libc::SIGBUS, 3) => b"BUS_OBJERR: a hardware error on the mapped object",
        (libc::SIGBUS, 4 | 5) => b"BUS_MCEERR: a machine check (memory hardware)",
        (libc::SIGSEGV, 1) => b"SEGV_MAPERR: nothing is mapped there",
        (libc::SIGSEGV, 2) => b"SEGV_ACCERR: mapped, but not with that access",
        (_, SI_KERNEL) => {
            b"SI_KERNEL: a general-protection or stack-segment fault, e.g. a non-canonical (wild) pointer"
        }
        (libc::SIGFPE, 1) => b"FPE_INTDIV: integer division by zero",
        (libc::SIGILL, 1) => b"ILL_ILLOPC: an illegal opcode",
        _ => b"code unknown",
    }
}

/// Writes where `addr` lies: the mapping's path and the offset, or that nothing is mapped.
/// `data`: a data address (its offset into the mapped file); else an instruction, given as
/// the address `addr2line -e LIB` takes: its distance from where the library's first
/// mapping (file offset 0) was loaded, which for a shared library or a PIE executable is
/// its link-time address.
fn where_is(line: &mut Line, addr: usize, data: bool, scratch: &mut Scratch) {
    let Some(m) = scan(scratch, |start, end, _| (start..end).contains(&addr)) else {
        line.push(b"outside every mapping");
        return;
    };
    let path = &m.path[..m.path_len];
    if path.is_empty() {
        line.push(b"in an anonymous mapping");
        return;
    }
    line.push(b"in ");
    line.push(path);
    if data {
        line.push(b" (file offset ");
        line.hex(addr - m.start + m.offset);
        line.push(b")");
    } else if let Some(base) = scan(scratch, |_, _, other| {
        other.offset == 0 && other.path() == path
    }) {
        line.push(b"+");
        line.hex(addr - base.start);
    }
}

/// One line of `/proc/self/maps`, parsed.
struct Mapping {
    start: usize,
    offset: usize,
    path: [u8; 256],
    path_len: usize,
}

impl Mapping {
    fn path(&self) -> &[u8] {
        &self.path[..self.path_len]
    }
}

/// The first line of `/proc/self/maps` that `pick(start, end, mapping)` takes, read without
/// allocating, through `scratch`.
fn scan(scratch: &mut Scratch, pick: impl Fn(usize, usize, &Mapping) -> bool) -> Option<Mapping> {
    // SAFETY: open/read/close are async-signal-safe.
    let fd = unsafe {
        libc::open(
            c"/proc/self/maps".as_ptr(),
            libc::O_RDONLY | libc::O_CLOEXEC,
        )
    };
    if fd < 0 {
        return None;
    }
    let Scratch { chunk, text } = scratch;
    let mut len = 0;
    let mut found = None;
    'read: loop {
        // SAFETY: reading into a buffer of its size.
        let n = unsafe { libc::read(fd, chunk.as_mut_ptr().cast(), chunk.len()) };
        if n <= 0 {
            break;
        }
        for &b in &chunk[..n as usize] {
            if b != b'\n' {
                if len < text.len() {
                    text[len] = b;
                    len += 1;
                }
                continue;
            }
            if let Some((_, _, m)) = parse(&text[..len]).filter(|(s, e, m)| pick(*s, *e, m)) {
                found = Some(m);
                break 'read;
            }
            len = 0;
        }
    }
    // SAFETY: closing the descriptor opened above.
    unsafe { libc::close(fd) };
    found
}

/// `START-END PERMS OFFSET DEV INODE [PATH]` → (start, end, the mapping).
fn parse(line: &[u8]) -> Option<(usize, usize, Mapping)> {
    let mut fields = line.split(|&b| b == b' ').filter(|f| !f.is_empty());
    let range = fields.next()?;
    let dash = range.iter().position(|&b| b == b'-')?;
    let start = hex(&range[..dash])?;
    let end = hex(&range[dash + 1..])?;
    let _perms = fields.next()?;
    let offset = hex(fields.next()?)?;
    let _dev = fields.next()?;
    let _inode = fields.next()?;
    let mut m = Mapping {
        start,
        offset,
        path: [0; 256],
        path_len: 0,
    };
    // The path is the rest of the line after the inode (it may hold spaces).
    let inode_end = nth_field_end(line, 5)?;
    let rest = line[inode_end..].trim_ascii_start();
    let n = rest.len().min(m.path.len());
    m.path[..n].copy_from_slice(&rest[..n]);
    m.path_len = n;
    Some((start, end, m))
}

/// Where the `n`th space-separated field of `line` ends.
fn nth_field_end(line: &[u8], n: usize) -> Option<usize> {
    let mut seen = 0;
    let mut in_field = false;
    for (i, &b) in line.iter().enumerate() {
        match (b == b' ', in_field) {
            (false, false) => in_field = true,
            (true, true) => {
                in_field = false;
                seen += 1;
                if seen == n {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    (in_field && seen + 1 == n).then_some(line.len())
}

fn hex(digits: &[u8]) -> Option<usize> {
    if digits.is_empty() || digits.len() > 16 {
        return None;
    }
    digits.iter().try_fold(0usize, |v, &d| {
        let x = (d as char).to_digit(16)? as usize;
        Some(v << 4 | x)
    })
}

/// A fixed line buffer (a handler may not allocate); what does not fit is cut.
struct Line {
    bytes: [u8; 1024],
    len: usize,
}

impl Line {
    fn new() -> Line {
        Line {
            bytes: [0; 1024],
            len: 0,
        }
    }

    fn push(&mut self, s: &[u8]) {
        // Keep the last byte for the newline.
        let room = self.bytes.len() - 1 - self.len;
        let n = s.len().min(room);
        self.bytes[self.len..self.len + n].copy_from_slice(&s[..n]);
        self.len += n;
        if s.ends_with(b"\n") && n < s.len() {
            self.bytes[self.len] = b'\n';
            self.len += 1;
        }
    }

    fn hex(&mut self, v: usize) {
        let mut digits = [0u8; 18];
        digits[0] = b'0';
        digits[1] = b'x';
        let mut n = 2;
        let mut started = false;
        for shift in (0..16).rev() {
            let d = (v >> (shift * 4)) & 0xf;
            if d != 0 || started || shift == 0 {
                started = true;
                digits[n] = b"0123456789abcdef"[d];
                n += 1;
            }
        }
        self.push(&digits[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_maps_line_is_read_with_its_path() {
        let (s, e, m) = parse(
            b"7f00a000-7f00c000 r-xp 00002000 08:01 1234        /usr/lib/x86_64-linux-gnu/lib vk.so",
        )
        .expect("parsed");
        assert_eq!((s, e, m.offset), (0x7f00_a000, 0x7f00_c000, 0x2000));
        assert_eq!(
            &m.path[..m.path_len],
            b"/usr/lib/x86_64-linux-gnu/lib vk.so"
        );
        let (_, _, anon) = parse(b"7f00a000-7f00c000 rw-p 00000000 00:00 0").expect("parsed");
        assert_eq!(anon.path_len, 0);
        assert!(parse(b"not a line").is_none());
    }

    #[test]
    fn this_processs_own_code_is_found_in_its_executable() {
        let here = this_processs_own_code_is_found_in_its_executable as *const () as usize;
        let mut scratch = Box::new(Scratch::new());
        let m = scan(&mut scratch, |s, e, _| (s..e).contains(&here)).expect("mapped");
        let path = String::from_utf8_lossy(m.path()).into_owned();
        let exe = std::env::current_exe().expect("exe");
        assert_eq!(std::path::Path::new(&path), exe, "{path}");
        let mut line = Line::new();
        line.hex(0x7f00_0a0b);
        line.hex(0);
        assert_eq!(&line.bytes[..line.len], b"0x7f000a0b0x0");
    }
}
