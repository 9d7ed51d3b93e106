! abut's Fortran module: the C ABI of include/abut.h through ISO_C_BINDING, with the same
! names. Handles are type(c_ptr); arrays are Fortran-shaped (real(c_double) :: x(3, n) passes
! positions, velocities and forces xyz per node, as the C ABI takes them); node, surface, set,
! pair and body ids are 0-based, as in C. Every function returns an integer(c_int32_t) status
! (ABUT_STATUS_OK = 0); abut_message() gives the thread's last error message.
!
! Build: compile this file with your code and link libabut (gfortran abut.f90 host.f90
! -L<dir> -labut). The C header's preamble states ownership, lifetimes and threads; they hold
! here unchanged.
module abut
  use, intrinsic :: iso_c_binding
  implicit none
  private :: c_strlen

  ! AbutStatus
  integer(c_int32_t), parameter :: ABUT_STATUS_OK = 0, ABUT_STATUS_NULL_POINTER = 1, &
    ABUT_STATUS_BAD_HANDLE = 2, ABUT_STATUS_LENGTH = 3, ABUT_STATUS_OUT_OF_RANGE = 4, &
    ABUT_STATUS_BAD_VALUE = 5, ABUT_STATUS_GEOMETRY = 6, ABUT_STATUS_DEVICE = 7, &
    ABUT_STATUS_CONTACT = 8, ABUT_STATUS_IO = 9, ABUT_STATUS_PANIC = 10
  ! AbutDeviceKind, AbutBackend
  integer(c_int32_t), parameter :: ABUT_DEVICE_KIND_AUTO = 0, ABUT_DEVICE_KIND_CPU = 1, &
    ABUT_DEVICE_KIND_GPU = 2
  integer(c_int32_t), parameter :: ABUT_BACKEND_ANY = 0, ABUT_BACKEND_VULKAN = 1, &
    ABUT_BACKEND_GL = 2, ABUT_BACKEND_METAL = 3, ABUT_BACKEND_DX12 = 4
  ! AbutFacetKind
  integer(c_int32_t), parameter :: ABUT_FACET_KIND_SEGMENTS = 2, ABUT_FACET_KIND_TRIANGLES = 3, &
    ABUT_FACET_KIND_QUADS = 4
  ! AbutEnforcement, AbutStiffness, AbutLawKind, AbutSliding
  integer(c_int32_t), parameter :: ABUT_ENFORCEMENT_PENALTY = 0, ABUT_ENFORCEMENT_KINEMATIC = 1
  integer(c_int32_t), parameter :: ABUT_STIFFNESS_AUTO = 0, ABUT_STIFFNESS_MODULUS = 1, &
    ABUT_STIFFNESS_ABSOLUTE = 2, ABUT_STIFFNESS_PER_AREA = 3
  integer(c_int32_t), parameter :: ABUT_LAW_KIND_DEFAULT = 0, ABUT_LAW_KIND_EXPONENTIAL = 1, &
    ABUT_LAW_KIND_TABULAR = 2, ABUT_LAW_KIND_SLOPE = 3
  integer(c_int32_t), parameter :: ABUT_SLIDING_FINITE = 0, ABUT_SLIDING_SMALL = 1, &
    ABUT_SLIDING_INFINITESIMAL = 2
  ! AbutSurfaceKind, AbutForceMode, AbutCstatus, AbutPairKind
  integer(c_int32_t), parameter :: ABUT_SURFACE_KIND_PLANE = 0, ABUT_SURFACE_KIND_SPHERE = 1, &
    ABUT_SURFACE_KIND_CYLINDER = 2, ABUT_SURFACE_KIND_LINE = 3, ABUT_SURFACE_KIND_CIRCLE = 4
  integer(c_int32_t), parameter :: ABUT_FORCE_MODE_WRITE = 0, ABUT_FORCE_MODE_ADD = 1
  integer(c_int32_t), parameter :: ABUT_CSTATUS_UNKNOWN = -1, ABUT_CSTATUS_OPEN = 0, &
    ABUT_CSTATUS_STICK = 1, ABUT_CSTATUS_SLIP = 2
  integer(c_int32_t), parameter :: ABUT_PAIR_KIND_MESHED = 0, ABUT_PAIR_KIND_RIGID = 1
  ! A node id that names no node (the fourth node of a triangle in a quad array).
  integer(c_int32_t), parameter :: ABUT_NO_NODE = -1

  ! AbutLaw
  type, bind(c) :: abut_law
    integer(c_int32_t) :: kind
    real(c_double) :: clearance, pressure, slope
    type(c_ptr) :: table
    integer(c_size_t) :: table_points
  end type

  ! AbutPairOptions (abut_pair_options_default fills it)
  type, bind(c) :: abut_pair_options
    integer(c_int32_t) :: enforcement, stiffness
    real(c_double) :: stiffness_value, stiffness_scale
    type(abut_law) :: law
    real(c_double) :: damping
    integer(c_int32_t) :: friction
    real(c_double) :: mu, mu_kinetic, decay, stick_stiffness
    integer(c_int32_t) :: sliding
    real(c_double) :: search_radius
    integer(c_int32_t) :: has_schedule
    integer(c_int32_t) :: schedule_interval
    real(c_double) :: schedule_budget
    integer(c_int32_t) :: schedule_wide_local, balanced
    integer(c_int32_t) :: balanced_surface
    real(c_double) :: balanced_weight, pass_weight
  end type

  ! AbutAnalytical
  type, bind(c) :: abut_analytical
    integer(c_int32_t) :: kind
    real(c_double) :: point(3), direction(3), radius
  end type

  ! AbutBodyState (rotation row by row)
  type, bind(c) :: abut_body_state
    real(c_double) :: position(3), rotation(9), velocity(3), angular_velocity(3)
  end type

  ! AbutReport
  type, bind(c) :: abut_report
    real(c_double) :: stable_dt, approach_dt, max_overclosure
    integer(c_int64_t) :: active, slipping, global_searches, fallbacks, unanchored, fast_nodes
    integer(c_int64_t) :: fastest_node
    integer(c_int32_t) :: fastest_pair
    real(c_double) :: fastest_distance, fastest_radius
    integer(c_int32_t) :: stable_dt_before_contact
  end type

  ! AbutKinematicReport
  type, bind(c) :: abut_kinematic_report
    integer(c_int64_t) :: active
    real(c_double) :: max_overclosure, max_overclosure_after, kinetic_energy_change
    real(c_double) :: total_force, friction_force
    integer(c_int64_t) :: fast_nodes, fastest_node
    real(c_double) :: fastest_distance, fastest_radius
  end type

  ! AbutOutputArrays (c_loc of your arrays, or c_null_ptr to skip one)
  type, bind(c) :: abut_output_arrays
    integer(c_size_t) :: len
    type(c_ptr) :: slaves, cstatus, copen, cpress, cshear1, cshear2, normal, force
  end type

  ! AbutOutputTotals
  type, bind(c) :: abut_output_totals
    real(c_double) :: cfn(3), cfs(3), contact_energy, frictional_dissipation
  end type

  interface
    integer(c_int32_t) function abut_version() bind(c, name="abut_version")
      import :: c_int32_t
    end function

    integer(c_int32_t) function abut_last_error(buf, cap, len) bind(c, name="abut_last_error")
      import :: c_int32_t, c_char, c_size_t
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len
    end function

    integer(c_int32_t) function abut_combined_increment(element_dt, contact_dt, safety, &
        contact_safety, dt) bind(c, name="abut_combined_increment")
      import :: c_int32_t, c_double
      real(c_double), value :: element_dt, contact_dt, safety, contact_safety
      real(c_double), intent(out) :: dt
    end function

    ! --- devices
    integer(c_int32_t) function abut_device_new(kind, backend, name, out) &
        bind(c, name="abut_device_new")
      import :: c_int32_t, c_char, c_ptr
      integer(c_int32_t), value :: kind, backend
      character(kind=c_char), intent(in), optional :: name(*)
      type(c_ptr), intent(out) :: out
    end function

    integer(c_int32_t) function abut_device_free(device) bind(c, name="abut_device_free")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: device
    end function

    integer(c_int32_t) function abut_device_describe(device, buf, cap, len) &
        bind(c, name="abut_device_describe")
      import :: c_int32_t, c_ptr, c_char, c_size_t
      type(c_ptr), value :: device
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len
    end function

    integer(c_int32_t) function abut_device_is_gpu(device, is_gpu) &
        bind(c, name="abut_device_is_gpu")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: device
      integer(c_int32_t), intent(out) :: is_gpu
    end function

    integer(c_int32_t) function abut_device_error(device, buf, cap, len) &
        bind(c, name="abut_device_error")
      import :: c_int32_t, c_ptr, c_char, c_size_t
      type(c_ptr), value :: device
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len
    end function

    ! --- models
    integer(c_int32_t) function abut_model_new(dim, out) bind(c, name="abut_model_new")
      import :: c_int32_t, c_ptr
      integer(c_int32_t), value :: dim
      type(c_ptr), intent(out) :: out
    end function

    integer(c_int32_t) function abut_model_free(model) bind(c, name="abut_model_free")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: model
    end function

    integer(c_int32_t) function abut_model_error(model, buf, cap, len) &
        bind(c, name="abut_model_error")
      import :: c_int32_t, c_ptr, c_char, c_size_t
      type(c_ptr), value :: model
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len
    end function

    integer(c_int32_t) function abut_model_node_count(model, count) &
        bind(c, name="abut_model_node_count")
      import :: c_int32_t, c_ptr, c_size_t
      type(c_ptr), value :: model
      integer(c_size_t), intent(out) :: count
    end function

    ! coords(dim, n), masses(n)
    integer(c_int32_t) function abut_model_add_nodes(model, coords, masses, n, first) &
        bind(c, name="abut_model_add_nodes")
      import :: c_int32_t, c_ptr, c_double, c_size_t
      type(c_ptr), value :: model
      real(c_double), intent(in) :: coords(*), masses(*)
      integer(c_size_t), value :: n
      integer(c_int32_t), intent(out), optional :: first
    end function

    ! nodes(kind, n_facets), 0-based ids
    integer(c_int32_t) function abut_model_add_surface(model, kind, nodes, n_facets, id) &
        bind(c, name="abut_model_add_surface")
      import :: c_int32_t, c_ptr, c_size_t
      type(c_ptr), value :: model
      integer(c_int32_t), value :: kind
      integer(c_int32_t), intent(in) :: nodes(*)
      integer(c_size_t), value :: n_facets
      integer(c_int32_t), intent(out) :: id
    end function

    integer(c_int32_t) function abut_model_add_node_set(model, nodes, n, areas, id) &
        bind(c, name="abut_model_add_node_set")
      import :: c_int32_t, c_ptr, c_size_t, c_double
      type(c_ptr), value :: model
      integer(c_int32_t), intent(in) :: nodes(*)
      integer(c_size_t), value :: n
      real(c_double), intent(in), optional :: areas(*)
      integer(c_int32_t), intent(out) :: id
    end function

    integer(c_int32_t) function abut_pair_options_default(options) &
        bind(c, name="abut_pair_options_default")
      import :: c_int32_t, abut_pair_options
      type(abut_pair_options), intent(out) :: options
    end function

    integer(c_int32_t) function abut_model_add_pair(model, slave, master, options, id) &
        bind(c, name="abut_model_add_pair")
      import :: c_int32_t, c_ptr, abut_pair_options
      type(c_ptr), value :: model
      integer(c_int32_t), value :: slave, master
      type(abut_pair_options), intent(in), optional :: options
      integer(c_int32_t), intent(out) :: id
    end function

    integer(c_int32_t) function abut_model_add_rigid_body(model, mass, inertia, surface, id) &
        bind(c, name="abut_model_add_rigid_body")
      import :: c_int32_t, c_ptr, c_double, abut_analytical
      type(c_ptr), value :: model
      real(c_double), value :: mass
      real(c_double), intent(in) :: inertia(9)
      type(abut_analytical), intent(in) :: surface
      integer(c_int32_t), intent(out) :: id
    end function

    integer(c_int32_t) function abut_model_add_rigid_pair(model, slave, body, softened, id) &
        bind(c, name="abut_model_add_rigid_pair")
      import :: c_int32_t, c_ptr, abut_law
      type(c_ptr), value :: model
      integer(c_int32_t), value :: slave, body
      type(abut_law), intent(in), optional :: softened
      integer(c_int32_t), intent(out) :: id
    end function

    integer(c_int32_t) function abut_model_add_rigid_part(model, nodes, n, mass, inertia, id) &
        bind(c, name="abut_model_add_rigid_part")
      import :: c_int32_t, c_ptr, c_size_t, c_double
      type(c_ptr), value :: model
      integer(c_int32_t), intent(in) :: nodes(*)
      integer(c_size_t), value :: n
      real(c_double), value :: mass
      real(c_double), intent(in) :: inertia(9)
      integer(c_int32_t), intent(out), optional :: id
    end function

    ! --- contacts
    integer(c_int32_t) function abut_contact_new(device, model, out) &
        bind(c, name="abut_contact_new")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: device, model
      type(c_ptr), intent(out) :: out
    end function

    integer(c_int32_t) function abut_contact_free(contact) bind(c, name="abut_contact_free")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: contact
    end function

    integer(c_int32_t) function abut_contact_error(contact, buf, cap, len) &
        bind(c, name="abut_contact_error")
      import :: c_int32_t, c_ptr, c_char, c_size_t
      type(c_ptr), value :: contact
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len
    end function

    integer(c_int32_t) function abut_contact_request_outputs(contact, yes) &
        bind(c, name="abut_contact_request_outputs")
      import :: c_int32_t, c_ptr
      type(c_ptr), value :: contact
      integer(c_int32_t), value :: yes
    end function

    integer(c_int32_t) function abut_contact_set_reference_increment(contact, dt) &
        bind(c, name="abut_contact_set_reference_increment")
      import :: c_int32_t, c_ptr, c_double
      type(c_ptr), value :: contact
      real(c_double), value :: dt
    end function

    ! x(3, n), v(3, n), forces(3, n)
    integer(c_int32_t) function abut_contact_penalty_step(contact, x, v, n_nodes, dt, forces, &
        mode) bind(c, name="abut_contact_penalty_step")
      import :: c_int32_t, c_ptr, c_double, c_size_t
      type(c_ptr), value :: contact
      real(c_double), intent(in) :: x(*), v(*)
      integer(c_size_t), value :: n_nodes
      real(c_double), value :: dt
      real(c_double), intent(inout) :: forces(*)
      integer(c_int32_t), value :: mode
    end function

    integer(c_int32_t) function abut_contact_kinematic_step(contact, x, v, n_nodes, bodies, &
        n_bodies, dt) bind(c, name="abut_contact_kinematic_step")
      import :: c_int32_t, c_ptr, c_double, c_size_t, abut_body_state
      type(c_ptr), value :: contact
      real(c_double), intent(inout) :: x(*), v(*)
      integer(c_size_t), value :: n_nodes
      type(abut_body_state), intent(inout), optional :: bodies(*)
      integer(c_size_t), value :: n_bodies
      real(c_double), value :: dt
    end function

    integer(c_int32_t) function abut_contact_adjust_initial_overclosure(contact, x, n_nodes, &
        bodies, n_bodies, dt, max_distance) &
        bind(c, name="abut_contact_adjust_initial_overclosure")
      import :: c_int32_t, c_ptr, c_double, c_size_t, abut_body_state
      type(c_ptr), value :: contact
      real(c_double), intent(inout) :: x(*)
      integer(c_size_t), value :: n_nodes
      type(abut_body_state), intent(in), optional :: bodies(*)
      integer(c_size_t), value :: n_bodies
      real(c_double), value :: dt
      real(c_double), intent(out), optional :: max_distance
    end function

    integer(c_int32_t) function abut_contact_report(contact, report) &
        bind(c, name="abut_contact_report")
      import :: c_int32_t, c_ptr, abut_report
      type(c_ptr), value :: contact
      type(abut_report), intent(out) :: report
    end function

    integer(c_int32_t) function abut_contact_kinematic_report(contact, report) &
        bind(c, name="abut_contact_kinematic_report")
      import :: c_int32_t, c_ptr, abut_kinematic_report
      type(c_ptr), value :: contact
      type(abut_kinematic_report), intent(out) :: report
    end function

    integer(c_int32_t) function abut_contact_warnings(contact, buf, cap, len, count) &
        bind(c, name="abut_contact_warnings")
      import :: c_int32_t, c_ptr, c_char, c_size_t
      type(c_ptr), value :: contact
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
      integer(c_size_t), intent(out), optional :: len, count
    end function

    integer(c_int32_t) function abut_contact_output_len(contact, kind, pair, pass, len) &
        bind(c, name="abut_contact_output_len")
      import :: c_int32_t, c_ptr, c_size_t
      type(c_ptr), value :: contact
      integer(c_int32_t), value :: kind, pair, pass
      integer(c_size_t), intent(out) :: len
    end function

    integer(c_int32_t) function abut_contact_output(contact, kind, pair, pass, arrays, totals) &
        bind(c, name="abut_contact_output")
      import :: c_int32_t, c_ptr, abut_output_arrays, abut_output_totals
      type(c_ptr), value :: contact
      integer(c_int32_t), value :: kind, pair, pass
      type(abut_output_arrays), intent(in) :: arrays
      type(abut_output_totals), intent(out), optional :: totals
    end function

    integer(c_int32_t) function abut_contact_state_size(contact, bytes) &
        bind(c, name="abut_contact_state_size")
      import :: c_int32_t, c_ptr, c_size_t
      type(c_ptr), value :: contact
      integer(c_size_t), intent(out) :: bytes
    end function

    integer(c_int32_t) function abut_contact_save_state(contact, buf, cap) &
        bind(c, name="abut_contact_save_state")
      import :: c_int32_t, c_ptr, c_int8_t, c_size_t
      type(c_ptr), value :: contact
      integer(c_int8_t), intent(out) :: buf(*)
      integer(c_size_t), value :: cap
    end function

    integer(c_int32_t) function abut_contact_restore_state(contact, buf, len) &
        bind(c, name="abut_contact_restore_state")
      import :: c_int32_t, c_ptr, c_int8_t, c_size_t
      type(c_ptr), value :: contact
      integer(c_int8_t), intent(in) :: buf(*)
      integer(c_size_t), value :: len
    end function
  end interface

contains

  ! The thread's last abut error message (empty: none yet).
  function abut_message() result(msg)
    character(len=:), allocatable :: msg
    character(kind=c_char) :: buf(4096)
    integer(c_size_t) :: n
    integer(c_int32_t) :: s
    integer :: k
    s = abut_last_error(buf, int(size(buf), c_size_t), n)
    n = min(n, int(size(buf) - 1, c_size_t))
    allocate (character(len=n) :: msg)
    do k = 1, int(n)
      msg(k:k) = buf(k)
    end do
    if (s /= ABUT_STATUS_OK) msg = "(abut_last_error failed)"
  end function

  ! Stops the program with abut's message when `status` is not ABUT_STATUS_OK.
  subroutine abut_check(status, what)
    integer(c_int32_t), intent(in) :: status
    character(len=*), intent(in) :: what
    if (status /= ABUT_STATUS_OK) then
      write (*, '(a, a, i0, a, a)') what, " failed (status ", status, "): ", abut_message()
      error stop 1
    end if
  end subroutine

  ! The length of a C string's text in `buf` (up to its NUL).
  pure integer function c_strlen(buf)
    character(kind=c_char), intent(in) :: buf(:)
    c_strlen = 0
    do while (c_strlen < size(buf))
      if (buf(c_strlen + 1) == c_null_char) exit
      c_strlen = c_strlen + 1
    end do
  end function

  ! A device's description (adapter and backend, or the CPU path).
  function abut_device_name(device) result(name)
    type(c_ptr), intent(in) :: device
    character(len=:), allocatable :: name
    character(kind=c_char) :: buf(512)
    integer :: k, n
    buf = c_null_char
    if (abut_device_describe(device, buf, int(size(buf), c_size_t)) /= ABUT_STATUS_OK) then
      name = "(unknown device)"
      return
    end if
    n = c_strlen(buf)
    allocate (character(len=n) :: name)
    do k = 1, n
      name(k:k) = buf(k)
    end do
  end function
end module abut
