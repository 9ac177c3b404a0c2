//! The `caustic` command.

#[global_allocator]
static ALLOCATOR: caustic::memory::CountingAllocator = caustic::memory::CountingAllocator;

fn main() -> std::process::ExitCode {
    caustic::cli::main()
}
