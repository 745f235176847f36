//! The hand-written header `include/probekit.h` against the Rust source:
//! every `#[no_mangle] extern "C"` function of `src/` is declared in
//! the header with the same return type and the same parameter types (Rust
//! types mapped to their C spellings), no other function is declared, and
//! the enum values and constants agree.

use std::collections::BTreeMap;
use std::sync::OnceLock;

const HEADER: &str = include_str!("../include/probekit.h");

/// The library's Rust source: every `.rs` file of `src/`, in name order.
fn lib() -> &'static str {
    static SOURCE: OnceLock<String> = OnceLock::new();
    SOURCE.get_or_init(|| {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .expect("read src/")
            .map(|e| e.expect("src/ entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "rs"))
            .collect();
        files.sort();
        assert!(!files.is_empty(), "no source files in {dir}");
        files
            .iter()
            .map(|p| std::fs::read_to_string(p).expect("read a source file"))
            .collect::<Vec<_>>()
            .join("\n")
    })
}

/// A signature as C spells it: return type and parameter types.
#[derive(Debug, PartialEq, Eq)]
struct Sig {
    ret: String,
    params: Vec<String>,
}

/// Collapses whitespace and puts `*` after a space: `const float *`.
fn norm(t: &str) -> String {
    t.replace('*', " * ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// C spelling of a Rust FFI type.
fn rust_to_c(t: &str) -> String {
    let t = t.trim();
    if let Some(rest) = t.strip_prefix("*const ") {
        return norm(&format!("const {} *", rust_to_c(rest)));
    }
    if let Some(rest) = t.strip_prefix("*mut ") {
        return norm(&format!("{} *", rust_to_c(rest)));
    }
    match t {
        "f32" => "float",
        "u8" => "uint8_t",
        "u32" => "uint32_t",
        "i32" => "int32_t",
        "usize" => "size_t",
        "c_char" => "char",
        "" => "void",
        other => other, // PkStatus, PkKind, PkProbes, ... keep their names.
    }
    .to_string()
}

/// Splits a parameter list at top-level commas.
fn split_params(s: &str) -> Vec<&str> {
    s.split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect()
}

/// Exported functions of the Rust source.
fn rust_functions() -> BTreeMap<String, Sig> {
    let mut out = BTreeMap::new();
    let mut rest = lib();
    while let Some(i) = rest.find("#[no_mangle]") {
        rest = &rest[i + 12..];
        let fn_at = rest.find("fn ").expect("fn after #[no_mangle]");
        let head = &rest[..fn_at];
        assert!(head.contains("extern \"C\""), "non-C export: {head}");
        let after = &rest[fn_at + 3..];
        let open = after.find('(').unwrap();
        let name = after[..open].trim().to_string();
        let close = open + after[open..].find(')').unwrap();
        let params = split_params(&after[open + 1..close])
            .into_iter()
            .map(|p| rust_to_c(p.split_once(':').expect("name: type").1))
            .collect();
        let brace = after[close..].find('{').unwrap() + close;
        let ret = after[close + 1..brace]
            .trim()
            .trim_start_matches("->")
            .trim();
        out.insert(
            name,
            Sig {
                ret: rust_to_c(ret),
                params,
            },
        );
    }
    out
}

/// The header without comments and preprocessor lines.
fn header_code() -> String {
    let mut s = String::new();
    let mut rest = HEADER;
    while let Some(i) = rest.find("/*") {
        s.push_str(&rest[..i]);
        let j = rest[i..].find("*/").expect("closed comment") + i + 2;
        rest = &rest[j..];
    }
    s.push_str(rest);
    s.lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Function declarations of the header (C type of each parameter, names dropped).
fn header_functions() -> BTreeMap<String, Sig> {
    let mut out = BTreeMap::new();
    for decl in header_code().split(';') {
        let decl = decl.replace('\n', " ");
        let Some(open) = decl.find("pk_") else {
            continue;
        };
        let Some(paren) = decl[open..].find('(').map(|p| p + open) else {
            continue;
        };
        let name = decl[open..paren].trim().to_string();
        let ret = norm(decl[..open].trim().rsplit('}').next().unwrap());
        let close = decl.rfind(')').unwrap();
        let params = split_params(&decl[paren + 1..close])
            .into_iter()
            .filter(|p| *p != "void")
            .map(|p| {
                // Drop the parameter name: the last identifier.
                let p = norm(p);
                let cut = p
                    .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .map_or(0, |i| i + 1);
                norm(&p[..cut])
            })
            .collect();
        out.insert(name, Sig { ret, params });
    }
    out
}

#[test]
fn every_exported_function_is_declared_with_matching_types() {
    let rust = rust_functions();
    let header = header_functions();
    assert!(rust.len() >= 25, "found only {} exports", rust.len());
    for (name, sig) in &rust {
        let h = header
            .get(name)
            .unwrap_or_else(|| panic!("{name} is exported but not declared in probekit.h"));
        assert_eq!(h, sig, "{name}: header vs Rust");
    }
    for name in header.keys() {
        assert!(
            rust.contains_key(name),
            "{name} is declared in probekit.h but not exported"
        );
    }
}

/// `Variant = value` pairs of `pub enum name` in the Rust source.
fn rust_enum(name: &str) -> Vec<(String, i64)> {
    let lib = lib();
    let start = lib.find(&format!("pub enum {name} {{")).unwrap();
    let body = &lib[start..start + lib[start..].find('}').unwrap()];
    body.lines()
        .filter_map(|l| l.trim().strip_suffix(','))
        .filter_map(|l| l.split_once(" = "))
        .map(|(n, v)| (n.trim().to_string(), v.trim().parse().unwrap()))
        .collect()
}

/// `NAME = value` pairs of `typedef enum name` in the header.
fn header_enum(name: &str) -> BTreeMap<String, i64> {
    let code = header_code();
    let start = code.find(&format!("typedef enum {name} {{")).unwrap();
    let body = &code[start + name.len() + 15..start + code[start..].find('}').unwrap()];
    body.split(',')
        .filter_map(|l| l.split_once('='))
        .map(|(n, v)| (n.trim().to_string(), v.trim().parse().unwrap()))
        .collect()
}

fn upper_snake(camel: &str) -> String {
    let mut s = String::new();
    for (i, c) in camel.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            s.push('_');
        }
        s.push(c.to_ascii_uppercase());
    }
    s
}

#[test]
fn enum_values_and_constants_agree() {
    let status = header_enum("PkStatus");
    let rust = rust_enum("PkStatus");
    assert_eq!(status.len(), rust.len());
    for (n, v) in rust {
        let c = if n == "Ok" {
            "PK_OK".to_string()
        } else {
            format!("PK_ERR_{}", upper_snake(&n))
        };
        assert_eq!(status.get(&c), Some(&v), "{c}");
    }
    let kind = header_enum("PkKind");
    let rust = rust_enum("PkKind");
    assert_eq!(kind.len(), rust.len());
    for (n, v) in rust {
        let c = format!("PK_KIND_{}", upper_snake(&n));
        assert_eq!(kind.get(&c), Some(&v), "{c}");
    }
    // The library's view of the values, not just the source text.
    assert_eq!(probekit_capi::PkStatus::Panic as i32, 9);
    assert_eq!(probekit_capi::PkKind::Invalid as i32, -1);

    let define = |name: &str| -> i64 {
        let line = HEADER
            .lines()
            .find(|l| l.starts_with(&format!("#define {name} ")))
            .unwrap_or_else(|| panic!("#define {name}"));
        line.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    assert_eq!(
        define("PK_ABI_VERSION"),
        probekit_capi::PK_ABI_VERSION as i64
    );
    assert_eq!(
        probekit_capi::pk_abi_version(),
        probekit_capi::PK_ABI_VERSION
    );
    // PK_INTERP_* values are the positions in the INTERPS table.
    let lib = lib();
    let table = lib.find("const INTERPS").unwrap();
    let table = &lib[table..table + lib[table..].find("];").unwrap()];
    let names: Vec<&str> = table
        .lines()
        .filter_map(|l| l.trim().strip_prefix("Interp::"))
        .map(|l| l.trim_end_matches(','))
        .collect();
    assert_eq!(names.len(), 5);
    for (i, n) in names.iter().enumerate() {
        assert_eq!(define(&format!("PK_INTERP_{}", upper_snake(n))), i as i64);
    }
}
