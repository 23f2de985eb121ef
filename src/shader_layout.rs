//! GLSL's block layout rules (GLSL 4.60 §4.4.5, "Standard Uniform Block Layout"), evaluated
//! at compile time by `shared_structs!` (src/shader_structs.rs) to check that each generated
//! `#[repr(C)]` struct has exactly the offsets and size GLSL gives its mirror.

/// The layout rule of the block a struct is read through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Uniform blocks: structs and arrays aligned to 16 bytes, array strides rounded up to 16.
    Std140,
    /// Storage blocks and push constants: the base alignments of the members themselves.
    Std430,
}

/// Base alignment and size of a GLSL type, in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub align: usize,
    pub size: usize,
}

const fn round_up(n: usize, to: usize) -> usize {
    n.div_ceil(to) * to
}

impl Layout {
    /// `float`, `int`, `uint`.
    pub const SCALAR: Layout = Layout { align: 4, size: 4 };

    /// A vector of `n` scalars: a `vec3` is aligned like a `vec4` but only 12 bytes long, so a
    /// scalar may follow it within the same 16 bytes.
    pub const fn vector(n: usize) -> Layout {
        Layout { align: if n == 2 { 8 } else { 16 }, size: 4 * n }
    }

    /// A column-major matrix of `columns` `vec4`s (an array of them, in both rules).
    pub const fn matrix(columns: usize) -> Layout {
        Layout { align: 16, size: 16 * columns }
    }

    /// An array of `n` elements of this type.
    pub const fn array(self, n: usize, rule: Rule) -> Layout {
        let align = match rule {
            Rule::Std140 => round_up(self.align, 16),
            Rule::Std430 => self.align,
        };
        Layout { align, size: round_up(self.size, align) * n }
    }

    /// Offset of member `i` of a struct whose members have these layouts.
    pub const fn offset(members: &[Layout], i: usize) -> usize {
        let mut offset = 0;
        let mut m = 0;
        while m <= i {
            offset = round_up(offset, members[m].align);
            if m < i {
                offset += members[m].size;
            }
            m += 1;
        }
        offset
    }

    /// A struct of these members: the largest member alignment (at least 16 under std140),
    /// and the end of its last member rounded up to it.
    pub const fn structure(members: &[Layout], rule: Rule) -> Layout {
        let mut align = match rule {
            Rule::Std140 => 16,
            Rule::Std430 => 1,
        };
        let mut m = 0;
        while m < members.len() {
            if members[m].align > align {
                align = members[m].align;
            }
            m += 1;
        }
        let end = match members.len() {
            0 => 0,
            n => Layout::offset(members, n - 1) + members[n - 1].size,
        };
        Layout { align, size: round_up(end, align) }
    }

    /// Panics (at compile time, where `shared_structs!` calls it) with the name of the first
    /// member whose Rust offset differs from its GLSL offset, or with the struct's name when
    /// the sizes differ.
    pub const fn check(
        struct_name: &str,
        names: &[&str],
        members: &[Layout],
        offsets: &[usize],
        size: usize,
        rule: Rule,
    ) {
        let mut m = 0;
        while m < members.len() {
            if Layout::offset(members, m) != offsets[m] {
                panic!("{}", names[m]);
            }
            m += 1;
        }
        if Layout::structure(members, rule).size != size {
            panic!("{}", struct_name);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Layout, Rule};

    const F: Layout = Layout::SCALAR;

    /// A scalar after a vec3 fills the vec3's fourth word; a vec3 after a scalar starts at the
    /// next 16 bytes.
    #[test]
    fn vec3_packs_a_following_scalar() {
        let members = [Layout::vector(3), F, Layout::vector(3), F];
        let offsets: Vec<_> = (0..4).map(|i| Layout::offset(&members, i)).collect();
        assert_eq!(offsets, [0, 12, 16, 28]);
        let members = [F, Layout::vector(3)];
        assert_eq!(Layout::offset(&members, 1), 16);
        assert_eq!(Layout::structure(&members, Rule::Std430), Layout { align: 16, size: 32 });
    }

    /// std140 rounds array strides and struct alignment up to 16 bytes; std430 does not.
    #[test]
    fn std140_rounds_arrays_and_structs_to_16_bytes() {
        assert_eq!(F.array(3, Rule::Std430), Layout { align: 4, size: 12 });
        assert_eq!(F.array(3, Rule::Std140), Layout { align: 16, size: 48 });
        assert_eq!(Layout::vector(2).array(2, Rule::Std140).size, 32);
        let pair = [F, F];
        assert_eq!(Layout::structure(&pair, Rule::Std430), Layout { align: 4, size: 8 });
        assert_eq!(Layout::structure(&pair, Rule::Std140), Layout { align: 16, size: 16 });
        assert_eq!(Layout::structure(&[Layout::matrix(4), Layout::vector(4)], Rule::Std140).size, 80);
    }

    /// The check names the first member out of place, or the struct when only its size differs.
    #[test]
    fn check_names_what_differs() {
        let members = [Layout::vector(3), F];
        Layout::check("S", &["a", "b"], &members, &[0, 12], 16, Rule::Std430);
        let e = std::panic::catch_unwind(|| Layout::check("S", &["a", "b"], &members, &[0, 16], 20, Rule::Std430));
        assert_eq!(e.unwrap_err().downcast_ref::<String>().map(String::as_str), Some("b"));
        let e = std::panic::catch_unwind(|| Layout::check("S", &["a", "b"], &members, &[0, 12], 20, Rule::Std430));
        assert_eq!(e.unwrap_err().downcast_ref::<String>().map(String::as_str), Some("S"));
    }
}
