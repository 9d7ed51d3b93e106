! An explicit host loop in Fortran calling abut once per increment through the abut module
! (capi/fortran/abut.f90, over libabut's C ABI).
!
! The model and loop of examples/host_loop.rs (a sheet of 8 x 8 point masses joined by springs
! thrown onto a fixed plate of 4 x 4 quads, penalty contact with Coulomb friction 0.3 and half
! of critical damping, 600 increments of 1e-4), with Fortran-shaped arrays x(3, n), v(3, n),
! f(3, n). Node ids are 0-based in abut's calls: node k is column k + 1.
!
!   cargo build --release -p abut-capi
!   gfortran -O2 -ffp-contract=off -Jtarget capi/fortran/abut.f90 examples/fortran/host_loop.f90 -Ltarget/release -labut -o host_loop_f
!   LD_LIBRARY_PATH=target/release ./host_loop_f [cpu|vulkan|gl|auto] [forces.bin]
program host_loop
  use, intrinsic :: iso_c_binding
  use abut
  implicit none
  integer, parameter :: dp = c_double
  integer, parameter :: nplate = 4, nsheet = 8, steps = 600
  integer, parameter :: np = (nplate + 1)**2, ns = nsheet*nsheet, n = np + ns
  integer, parameter :: nspring = 2*nsheet*(nsheet - 1)
  real(dp), parameter :: h = 0.1_dp, ks = 200.0_dp, g = 9.81_dp, dt = 1.0e-4_dp
  real(dp) :: x(3, n), v(3, n), f(3, n), fs(3, nspring), m(n), d(3), l, c, centre(3)
  integer(c_int32_t) :: quads(4, nplate*nplate), sheet(ns), plate, slaves, pair
  integer :: si(nspring), sj(nspring), i, j, k, s, a, step, touching, u
  integer(c_int64_t) :: most
  type(c_ptr) :: device, model, contact
  type(abut_pair_options) :: options
  type(abut_report) :: report
  character(len=32) :: which
  character(len=1024) :: path

  which = "cpu"
  path = ""
  if (command_argument_count() >= 1) call get_command_argument(1, which)
  if (command_argument_count() >= 2) call get_command_argument(2, path)

  k = 0
  do j = 0, nplate
    do i = 0, nplate
      k = k + 1
      x(:, k) = [-1.0_dp + 0.5_dp*real(i, dp), -1.0_dp + 0.5_dp*real(j, dp), 0.0_dp]
      m(k) = 1.0_dp
    end do
  end do
  do j = 0, nplate - 1
    do i = 0, nplate - 1
      a = j*(nplate + 1) + i
      quads(:, j*nplate + i + 1) = [a, a + 1, a + nplate + 2, a + nplate + 1]
    end do
  end do
  do j = 0, nsheet - 1
    do i = 0, nsheet - 1
      k = k + 1
      x(:, k) = [h*real(i, dp) - 0.35_dp, h*real(j, dp) - 0.35_dp, 0.001_dp]
      m(k) = 0.01_dp
      sheet(k - np) = k - 1
    end do
  end do
  ! springs between 1-based columns: along x row by row, then along y
  s = 0
  do j = 0, nsheet - 1
    do i = 0, nsheet - 2
      s = s + 1
      si(s) = np + j*nsheet + i + 1
      sj(s) = np + j*nsheet + i + 2
    end do
  end do
  do j = 0, nsheet - 2
    do i = 0, nsheet - 1
      s = s + 1
      si(s) = np + j*nsheet + i + 1
      sj(s) = np + (j + 1)*nsheet + i + 1
    end do
  end do

  select case (trim(which))
  case ("cpu")
    call abut_check(abut_device_new(ABUT_DEVICE_KIND_CPU, 0, out=device), "device")
  case ("vulkan")
    call abut_check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_VULKAN, out=device), "device")
  case ("gl")
    call abut_check(abut_device_new(ABUT_DEVICE_KIND_GPU, ABUT_BACKEND_GL, out=device), "device")
  case default
    call abut_check(abut_device_new(ABUT_DEVICE_KIND_AUTO, 0, out=device), "device")
  end select
  call abut_check(abut_model_new(3, model), "model")
  call abut_check(abut_model_add_nodes(model, x, m, int(n, c_size_t)), "nodes")
  call abut_check(abut_model_add_surface(model, ABUT_FACET_KIND_QUADS, quads, &
                                         int(nplate*nplate, c_size_t), plate), "plate")
  call abut_check(abut_model_add_node_set(model, sheet, int(ns, c_size_t), id=slaves), "sheet")
  call abut_check(abut_pair_options_default(options), "options")
  options%friction = 1
  options%mu = 0.3_dp
  options%damping = 0.5_dp
  call abut_check(abut_model_add_pair(model, slaves, plate, options, pair), "pair")
  call abut_check(abut_contact_new(device, model, contact), "contact")
  call abut_check(abut_model_free(model), "free model")

  if (len_trim(path) > 0) open (newunit=u, file=trim(path), access="stream", &
                                form="unformatted", status="replace")
  v = 0.0_dp
  do k = np + 1, n
    v(:, k) = [1.0_dp, 0.25_dp, -0.2_dp]
  end do
  touching = 0
  most = 0
  do step = 1, steps
    f = 0.0_dp
    do s = 1, nspring
      d = x(:, sj(s)) - x(:, si(s))
      l = sqrt((d(1)*d(1) + d(2)*d(2)) + d(3)*d(3))
      c = (ks*(l - h))/l
      fs(:, s) = c*d
    end do
    do s = 1, nspring
      f(:, si(s)) = f(:, si(s)) + fs(:, s)
    end do
    do s = 1, nspring
      f(:, sj(s)) = f(:, sj(s)) - fs(:, s)
    end do
    do k = np + 1, n
      f(3, k) = f(3, k) - m(k)*g
    end do

    call abut_check(abut_contact_penalty_step(contact, x, v, int(n, c_size_t), dt, f, &
                                              ABUT_FORCE_MODE_ADD), "penalty step")
    call abut_check(abut_contact_report(contact, report), "report")
    if (report%active > 0) touching = touching + 1
    most = max(most, report%active)
    if (len_trim(path) > 0) write (u) f

    do k = np + 1, n
      do a = 1, 3
        v(a, k) = v(a, k) + (dt*f(a, k))/m(k)
        x(a, k) = x(a, k) + dt*v(a, k)
      end do
    end do
  end do
  if (len_trim(path) > 0) close (u)
  centre = 0.0_dp
  do k = np + 1, n
    centre = centre + x(:, k)
  end do
  centre = centre/real(ns, dp)
  write (*, '(a, a, a, i0, a, i0, a, i0, a, f0.6, a, f0.6, a, f0.6, a)') "fortran on ", &
    abut_device_name(device), ": ", steps, " increments, in contact in ", touching, &
    ", at most ", most, " nodes; sheet centre (", centre(1), ", ", centre(2), ", ", &
    centre(3), ")"
  call abut_check(abut_contact_free(contact), "free contact")
  call abut_check(abut_device_free(device), "free device")
end program host_loop
