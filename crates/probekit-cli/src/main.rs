//! The `probekit` command-line tool: a thin layer over the `probekit` library.

fn main() {
    println!("probekit");
}
