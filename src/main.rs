//! The `caustic` command.

#[global_allocator]
static ALLOCATOR: caustic::memory::CountingAllocator = caustic::memory::CountingAllocator;

fn main() -> std::process::ExitCode {
    if !cpu_is_supported() {
        eprintln!("caustic: this build needs an x86-64 CPU with SSE4.2 and POPCNT (x86-64-v2, see .cargo/config.toml); rebuild without that setting for this one");
        return std::process::ExitCode::FAILURE;
    }
    caustic::memory::prefer_small_pages();
    caustic::cli::main()
}

/// Whether the CPU has what the build assumes (.cargo/config.toml). The check reads CPUID itself:
/// the standard feature test answers from the build's own assumptions.
#[cfg(target_arch = "x86_64")]
fn cpu_is_supported() -> bool {
    const SSE4_2: u32 = 1 << 20;
    const POPCNT: u32 = 1 << 23;
    let ecx = std::arch::x86_64::__cpuid(1).ecx;
    ecx & SSE4_2 != 0 && ecx & POPCNT != 0
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_is_supported() -> bool {
    true
}
