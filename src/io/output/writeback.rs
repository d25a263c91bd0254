//! The output's temporary file, whose pages the kernel is asked to start writing out while
//! the render goes on ([`EarlyWriteback`]).
//!
//! A render's file is written to a temporary name and renamed over the target. On ext4 a
//! rename that replaces a file first has the kernel allocate blocks for, and start writing,
//! every page of the new file still waiting in memory (`auto_da_alloc`, so that a crash just
//! after the rename cannot leave an empty file where the old one was): for a 4K render's
//! 32 MB that was 10-14 ms of a serial tail after the last band, on every overwrite. Asking
//! for the writeback of what has been written every few megabytes (`sync_file_range` with
//! `SYNC_FILE_RANGE_WRITE`: start it, do not wait) does the same work early, spread over the
//! render, and leaves the rename almost nothing of it; the kernel's own protection is
//! untouched, it just finds the pages under way. Elsewhere than Linux it does nothing.
//!
//! One of the crate's `unsafe` places, kept to the system call.

use std::fs::File;
use std::io::{Result, Seek, SeekFrom, Write};

/// Bytes written between two requests.
const STEP: u64 = 4 << 20;

/// A file whose written pages the kernel is asked to start writing out every [`STEP`]
/// bytes; otherwise the file itself.
pub(crate) struct EarlyWriteback {
    file: File,
    /// Bytes written since the last request.
    since: u64,
    /// Requests made (for the tests).
    requests: u32,
}

impl EarlyWriteback {
    pub(crate) fn new(file: File) -> Self {
        EarlyWriteback {
            file,
            since: 0,
            requests: 0,
        }
    }

    /// Requests made so far.
    #[cfg(test)]
    pub(crate) fn requests(&self) -> u32 {
        self.requests
    }

    /// Ask the kernel to start writing out the file's dirty pages (all of them: pages
    /// already under way or clean are passed over). A hint: its failure changes nothing that
    /// the file will hold, so it is ignored.
    fn start_writeback(&mut self) {
        self.requests += 1;
        #[cfg(target_os = "linux")]
        {
            use std::os::fd::AsRawFd;
            let fd = self.file.as_raw_fd();
            #[allow(unsafe_code)]
            // SAFETY: `fd` is the open descriptor of `self.file`, borrowed for the call; the
            // call passes no memory, only asks the kernel to start writeback of the file's
            // range [0, end) and returns, reading or changing nothing of the process.
            unsafe {
                libc::sync_file_range(fd, 0, 0, libc::SYNC_FILE_RANGE_WRITE);
            }
        }
    }
}

impl Write for EarlyWriteback {
    fn write(&mut self, buf: &[u8]) -> Result<usize> {
        let n = self.file.write(buf)?;
        self.since += n as u64;
        if self.since >= STEP {
            self.since = 0;
            self.start_writeback();
        }
        Ok(n)
    }

    fn flush(&mut self) -> Result<()> {
        self.file.flush()
    }
}

impl Seek for EarlyWriteback {
    fn seek(&mut self, pos: SeekFrom) -> Result<u64> {
        self.file.seek(pos)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// The bytes are the file's, whatever the seeks, and a request goes out every `STEP`.
    #[test]
    fn writes_and_seeks_as_the_file() {
        let path = std::env::temp_dir().join(format!("whitted-wb-{}.bin", std::process::id()));
        let mut w = EarlyWriteback::new(File::create(&path).unwrap());
        let block: Vec<u8> = (0..1_000_003u32).map(|i| (i * 7 % 251) as u8).collect();
        for _ in 0..10 {
            w.write_all(&block).unwrap();
        }
        // (a request at the write that passes 4 MiB since the last one: the 5th and 10th)
        assert_eq!(w.requests(), 2);
        w.seek(SeekFrom::Start(5)).unwrap();
        w.write_all(b"header").unwrap();
        w.seek(SeekFrom::End(0)).unwrap();
        w.write_all(b"end").unwrap();
        w.flush().unwrap();
        drop(w);
        let mut got = Vec::new();
        File::open(&path).unwrap().read_to_end(&mut got).unwrap();
        std::fs::remove_file(&path).unwrap();
        let mut want: Vec<u8> = block.repeat(10);
        want[5..11].copy_from_slice(b"header");
        want.extend_from_slice(b"end");
        assert!(got == want);
    }
}
