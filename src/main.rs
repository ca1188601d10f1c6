fn main() {
    println!("dda3d: under construction");
}
